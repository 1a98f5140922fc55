// `vdiso-mpi extract`: vdiso extract's command line (cli/extract_options.h), shared by the
// ranks. The full surface (octree) by runs of bricks, welded into one PLY written together
// (mpi/extract_across_ranks.h); the view-dependent surface (sage, wise) by parts of the image or
// of the volume, gathered on rank 0 for the picture and the mesh (mpi/view_across_ranks.h).
#include <cstdio>
#include <cstring>
#include <optional>
#include <string>
#include <vector>

#include "app/extract_stats_json.h"
#include "app/frame_files.h"
#include "cache/brick_cache.h"
#include "cache/cache_plan.h"
#include "cli/args.h"
#include "cli/extract_options.h"
#include "core/orientation.h"
#include "core/view_presets.h"
#include "io/atomic_output.h"
#include "io/json.h"
#include "io/mesh/mesh_writer.h"
#include "io/process_stats.h"
#include "io/store/brick_store.h"
#include "mpi/cli/commands.h"
#include "mpi/extract_across_ranks.h"
#include "mpi/rank_status.h"
#include "mpi/view_across_ranks.h"

namespace vdiso::mpi::cli {

namespace {

using vdiso::cli::ExtractOptions;
using vdiso::cli::UsageError;

constexpr const char* kHelp =
    "usage: mpirun -np N vdiso-mpi extract FILE.vdiso --iso V [options]\n"
    "\n"
    "vdiso extract's command line, shared by the ranks of the job (each opens FILE.vdiso with\n"
    "its own cache of --cache-mb):\n"
    "  --method octree (default)  the full surface: each rank extracts a contiguous run of the\n"
    "                             active bricks (balanced by their sub-blocks holding V), the\n"
    "                             ranks weld their borders and write one PLY together, the file\n"
    "                             'vdiso extract' writes, byte for byte (-o MESH.ply or .stl)\n"
    "  --method sage|wise         what the camera sees, shared by --partition; rank 0 gathers\n"
    "                             the ranks' surfaces for --png, -o (any mesh format) and\n"
    "                             --points-out\n"
    "  --partition image|object   sage/wise: image (default): each rank a part of the image's\n"
    "                             columns, reading only the bricks visible there; object: each\n"
    "                             rank a depth slab of the volume, the ranks trading coverage\n"
    "                             masks front to back as they go, so slabs behind skip what\n"
    "                             slabs in front hide (full resolution: --lod-error 0, one\n"
    "                             thread per rank)\n"
    "  --exchange-bricks N        object: bricks a rank extracts between coverage trades\n"
    "                             (default 4)\n"
    "  --threads N                per rank (default 1: the ranks are the parallelism)\n"
    "  --stats FILE               written by rank 0, with \"ranks\" and \"per_rank\"\n"
    "\n"
    "Not under MPI (run them with vdiso): --method noise, --path, --oracle, --level, --smooth,\n"
    "--decimate, --largest, --min-piece; with octree also --png and meshes other than .ply, .stl.\n"
    "A failure on any rank ends the job naming the rank, and leaves no output.\n"
    "\n"
    "The options, as vdiso extract takes them:\n\n";

struct MpiExtractOptions {
    ExtractOptions extract;
    ViewPartition partition = ViewPartition::Image;
    bool partitionGiven = false, exchangeGiven = false;
    int exchangeBricks = 4;
};

// Takes out vdiso-mpi's own options, parses the rest as vdiso extract does, and refuses what is
// not under MPI.
MpiExtractOptions parse(int argc, char** argv) {
    MpiExtractOptions m;
    std::vector<char*> rest;
    for (int i = 0; i < argc; ++i) {
        const std::string a = argv[i];
        if (a == "--partition" || a == "--exchange-bricks") {
            if (i + 1 >= argc) throw UsageError(a + " needs a value");
            const std::string value = argv[++i];
            if (a == "--exchange-bricks") {
                m.exchangeBricks = int(vdiso::cli::parseInt(a, value, 1, 1 << 20));
                m.exchangeGiven = true;
            } else if (value == "image" || value == "object") {
                m.partition = value == "image" ? ViewPartition::Image : ViewPartition::Object;
                m.partitionGiven = true;
            } else {
                throw UsageError("--partition expects image or object, not '" + value + "'");
            }
            continue;
        }
        rest.push_back(argv[i]);
    }
    ExtractOptions& o = m.extract = vdiso::cli::parseExtractOptions(int(rest.size()), rest.data());
    if (o.help) return m;
    // vdiso extract's settings are checked by its session (app/extract_session.h); the ranks'
    // extractions take them field by field, so they are checked here, once (SettingsError,
    // named as flags).
    checkExtractSettings(o);
    const bool view = vdiso::isViewDependent(o.method);
    if (o.method == "noise") throw UsageError("--method noise is not under MPI (octree is): run it with vdiso");
    if (o.orbitFrames > 0 || !o.pathFile.empty()) throw UsageError("--path is not under MPI: run it with vdiso");
    if (o.oracle) throw UsageError("--oracle is not under MPI: run it with vdiso");
    if (o.level != 0) throw UsageError("--level is not under MPI: run it with vdiso");
    if (o.post.any())
        throw UsageError("--smooth, --decimate, --largest and --min-piece are not under MPI: run them with vdiso");
    if (o.threads == 0) o.threads = 1;
    if (m.exchangeGiven && (!view || m.partition != ViewPartition::Object))
        throw UsageError("--exchange-bricks applies to --partition object");
    if (!view) {
        if (m.partitionGiven) throw UsageError("--partition applies to --method sage or wise");
        if (!o.pngPath.empty())
            throw UsageError("--png with --method octree is not under MPI (sage draws the same picture): run it "
                             "with vdiso");
        if (!o.meshPath.empty() && vdiso::meshFormatFor(o.meshPath) != MeshFormat::Ply &&
            vdiso::meshFormatFor(o.meshPath) != MeshFormat::Stl)
            throw UsageError(o.meshPath + ": the octree method writes .ply and .stl meshes under MPI");
    } else if (m.partition == ViewPartition::Object) {
        if (o.lodErrorGiven && o.lodError > 0)
            throw UsageError("--partition object extracts at full resolution (--lod-error 0): a coarser level's "
                             "brick reaches across the ranks' slabs; --partition image takes --lod-error");
        o.lodError = 0;
        if (o.threads != 1) throw UsageError("--partition object runs one thread per rank (--threads 1)");
    }
    return m;
}

std::string octreeStats(const ExtractOptions& o, const RanksExtractResult& r) {
    JsonObject s;
    addFrameHeader(s, o, r.source, o.threads, r.stats, 0, !o.meshPath.empty());
    s.add("ranks", r.ranks);
    s.add("extract_s", r.seconds).add("read_method", r.readMethod);
    s.add("bricks_loaded", r.bricksLoaded).add("bytes_read", r.bytesRead);
    addTraversalCounters(s, o.method, r.stats);
    s.add("partition_weight", "active sub-blocks");
    std::string perRank = "[";
    for (size_t k = 0; k < r.perRank.size(); ++k) {
        const RankExtractFigures& f = r.perRank[k];
        JsonObject p;
        p.add("rank", int64_t(k)).add("bricks", f.bricks).add("first_brick", f.firstBrick);
        p.add("last_brick", f.lastBrick).add("weight", f.weight);
        p.add("bricks_loaded", f.bricksLoaded).add("bytes_read", f.bytesRead);
        p.add("triangles", f.triangles).add("vertices_owned", f.verticesOwned);
        p.add("vertices_borrowed", f.verticesBorrowed).add("weld_bytes_sent", f.weldBytesSent);
        p.add("mesh_bytes", f.meshBytes);
        p.add("seconds", f.seconds).add("extract_s", f.extractSeconds);
        p.add("io_s", f.ioSeconds).add("decode_s", f.decodeSeconds);
        perRank += (k ? ", " : "") + p.str();
    }
    s.addRaw("per_rank", perRank + "]");
    s.add("peak_rss_mb_rank0", peakRssMb());
    return s.str();
}

std::string viewStats(const MpiExtractOptions& m, const BrickStoreReader& store, const RanksViewResult& r,
                      const std::string& viewName, int threads, std::optional<double> drawSeconds) {
    const ExtractOptions& o = m.extract;
    const ExtractStats& stats = r.stats;
    JsonObject s;
    addFrameHeader(s, o, frameSourceOf(store), threads, stats, stats.view.points, !o.meshPath.empty() || !o.pointsPath.empty());
    s.add("ranks", r.ranks).add("partition", r.partition == ViewPartition::Image ? "image" : "object");
    if (r.partition == ViewPartition::Object) {
        s.add("slab_axis", std::string(1, "xyz"[r.axis])).add("eye_slab", r.eyeSlab);
        s.add("exchange_bricks", m.exchangeBricks).add("coverage_rounds", r.rounds);
        s.add("coverage_bytes_per_rank", r.maskBytes);
    }
    s.add("gathered_bytes", r.gatheredBytes);
    s.add("extract_s", r.seconds).add("read_method", store.readMethod());
    s.add("bricks_loaded", r.bricksLoaded).add("bytes_read", r.bytesRead);
    addTraversalCounters(s, o.method, stats);
    if (drawSeconds) s.add("draw_s", *drawSeconds);
    s.add("view", viewName);
    std::string perRank = "[";
    for (size_t k = 0; k < r.perRank.size(); ++k) {
        const RankViewFigures& f = r.perRank[k];
        JsonObject p;
        p.add("rank", int64_t(k));
        if (r.partition == ViewPartition::Image)
            p.add("first_column", int64_t(f.partBegin)).add("end_column", int64_t(f.partEnd));
        else
            p.add("first_layer", int64_t(f.partBegin)).add("end_layer", int64_t(f.partEnd));
        p.add("bricks_loaded", f.bricksLoaded).add("bytes_read", f.bytesRead);
        p.add("bricks_active", f.bricksActive).add("triangles", f.triangles).add("points", f.points);
        p.add("culled_region", f.culledByRegion).add("culled_occlusion", f.culledByOcclusion);
        p.add("seconds", f.seconds).add("io_s", f.ioSeconds).add("decode_s", f.decodeSeconds);
        perRank += (k ? ", " : "") + p.str();
    }
    s.addRaw("per_rank", perRank + "]");
    s.add("peak_rss_mb_rank0", peakRssMb());
    return s.str();
}

// Rank 0 writes the statistics and prints the summary.
void report(const ExtractOptions& o, const std::string& json, const std::string& summary) {
    writeStats(o.statsPath, json, o.overwrite);
    if (!o.quiet && o.statsPath != "-") std::printf("%s\n", summary.c_str());
}

int runOctree(const Communicator& comm, const ExtractOptions& o) {
    RanksExtractOptions run;
    run.store = o.input;
    run.remote = o.remote;
    run.settings = o;
    run.meshPath = o.meshPath;
    run.overwrite = o.overwrite;
    run.cold = o.cold;
    const RanksExtractResult r = extractOctreeAcrossRanks(comm, run);
    runPhase(comm, [&] {
        if (comm.rank() != 0) return;
        char line[256];
        std::snprintf(line, sizeof line,
                      "octree iso %g on %d ranks: %llu triangles, %llu vertices, %.3f s, %llu bricks read (%.1f MB)",
                      *o.iso, r.ranks, (unsigned long long)r.stats.triangles, (unsigned long long)r.stats.vertices, r.seconds,
                      (unsigned long long)r.bricksLoaded, double(r.bytesRead) / 1e6);
        report(o, octreeStats(o, r), line);
    }, exitCodeOf, vdiso::cli::messageOf);
    return 0;
}

int runView(const Communicator& comm, const MpiExtractOptions& m) {
    const ExtractOptions& o = m.extract;
    std::optional<BrickStoreReader> store;
    std::optional<BrickCache> cache;
    Camera camera;
    ViewChoice view;
    RanksViewOptions run;
    runPhase(comm, [&] {
        store.emplace(o.input, StoreOpenOptions{o.cold ? ReadMode::Cold : ReadMode::Buffered, o.remote});
        cache.emplace(*store, o.cacheMb << 20);
        camera = vdiso::cli::extractCameras(o, store->volume(), view).front();
        vdiso::ExtractSettings settings = o;
        if (store->readsRemotely()) vdiso::adaptToRemoteStore(settings);  // read-ahead as vdiso extract's session sets it
        run.view = vdiso::viewExtractOptions(settings, vdiso::planCache(settings, *cache, settings.threads));
        run.partition = m.partition;
        run.exchangeBricks = m.exchangeBricks;
        run.gather = !o.meshPath.empty() || !o.pngPath.empty() || !o.pointsPath.empty();
        if (m.partition == ViewPartition::Image && comm.size() > camera.width)
            throw UsageError("--partition image: " + std::to_string(comm.size()) + " ranks for an image " +
                             std::to_string(camera.width) + " pixels wide (one column each at least)");
    }, exitCodeOf, vdiso::cli::messageOf);
    RanksViewResult r = extractViewAcrossRanks(comm, *cache, camera, run);
    runPhase(comm, [&] {
        if (comm.rank() != 0) return;
        const SpaceTransform transform =
            o.physicalMeshes.value_or(true) ? volumeToPhysical(store->volume()) : SpaceTransform{};
        const std::optional<double> drawSeconds = writeFrameFiles(
            {o.meshPath, o.pointsPath, o.pngPath, o.overwrite, o.meshCompress}, r.mesh, r.points, &camera, transform);
        char line[320];
        std::snprintf(line, sizeof line,
                      "%s iso %g on %d ranks by %s: %llu triangles, %llu points, %.3f s, %llu bricks read (%.1f MB)",
                      o.method.c_str(), *o.iso, r.ranks, r.partition == ViewPartition::Image ? "image" : "object",
                      (unsigned long long)r.stats.triangles, (unsigned long long)r.stats.view.points, r.seconds,
                      (unsigned long long)r.bricksLoaded, double(r.bytesRead) / 1e6);
        report(o, viewStats(m, *store, r, o.cameraPath.empty() ? viewChoiceName(view) : o.cameraPath, run.view.threads,
                            drawSeconds),
               line);
    }, exitCodeOf, vdiso::cli::messageOf);
    return 0;
}

}  // namespace

int runExtractAcrossRanks(const Communicator& comm, int argc, char** argv) {
    MpiExtractOptions m;
    // The same parse on every rank; existing outputs refused by rank 0 before any work.
    runPhase(comm, [&] {
        m = parse(argc, argv);
        const ExtractOptions& o = m.extract;
        if (o.help || comm.rank() != 0) return;
        vdiso::cli::refuseExistingOutputs({&o.meshPath, &o.pngPath, &o.statsPath, &o.pointsPath}, o.overwrite);
    }, exitCodeOf, vdiso::cli::messageOf);
    if (m.extract.help) {
        if (comm.rank() == 0) {
            std::fputs(kHelp, stdout);
            std::fputs(vdiso::cli::kExtractHelp, stdout);
        }
        return 0;
    }
    return vdiso::isViewDependent(m.extract.method) ? runView(comm, m) : runOctree(comm, m.extract);
}

}  // namespace vdiso::mpi::cli
