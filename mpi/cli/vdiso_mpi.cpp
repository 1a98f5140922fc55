// vdiso-mpi: vdiso's commands shared among the ranks of an mpirun job. A separate executable,
// so that vdiso itself neither links nor starts MPI. For now: `extract --method octree` with a
// .ply mesh; everything else is refused with a message saying so.
//
// Errors: every rank parses the same argv, so usage errors are the same on all of them and
// rank 0 alone prints them; a failure while working is agreed on collectively
// (mpi/rank_status.h) and rank 0 prints the first failing rank's message. Every rank then
// exits with the same code: 2 for wrong usage, 1 for an error.
#include <cstdio>
#include <cstring>
#include <exception>
#include <optional>
#include <string>

#include "core/brick_extractor.h"
#include "io/atomic_output.h"
#include "io/json.h"
#include "io/mesh_writer.h"
#include "io/process_stats.h"
#include "mpi/communicator.h"
#include "mpi/extract_across_ranks.h"
#include "mpi/rank_status.h"
#include "tools/args.h"

namespace {

using namespace vdiso;
using namespace vdiso::cli;

constexpr const char* kUsage =
    "usage: mpirun -np N vdiso-mpi <command> [options]\n"
    "\n"
    "commands (under MPI so far):\n"
    "  extract FILE.vdiso --iso V -o MESH.ply   full extraction (octree), bricks shared among\n"
    "                                           the ranks, one welded mesh written together\n"
    "\n"
    "convert, synth, info, compare and serve are not yet under MPI: run them with vdiso.\n";

constexpr const char* kExtractHelp =
    "usage: mpirun -np N vdiso-mpi extract FILE.vdiso --iso V [options]\n"
    "\n"
    "Extracts the isosurface at V with the ranks of the job: each takes a contiguous run of\n"
    "the active bricks (balanced by their sub-blocks holding V), extracts it, and the ranks\n"
    "weld their borders and write one PLY together. The file is the one 'vdiso extract' writes,\n"
    "byte for byte. A failure on any rank leaves no output.\n"
    "\n"
    "  --iso V                   isovalue\n"
    "  --method octree           the only method under MPI so far\n"
    "  -o, --output MESH.ply     the mesh (binary PLY; other formats not yet under MPI)\n"
    "  --mesh-space physical|volume   as vdiso extract (default physical)\n"
    "  --stats STATS.json        statistics, written by rank 0, with \"ranks\" and \"per_rank\"\n"
    "                            ('-' for stdout)\n"
    "  --metacell M              meta-cell size in cells, 1 to 32 (default 4)\n"
    "  --threads N               extraction threads per rank (default 1: the ranks are the\n"
    "                            parallelism)\n"
    "  --cache-mb N              brick cache budget per rank in MB (default 1024)\n"
    "  --force                   replace existing output files\n"
    "  --quiet                   no summary\n";

struct MpiExtractCli {
    mpi::RanksExtractOptions run;
    std::optional<double> iso;
    std::string statsPath;
    bool quiet = false, help = false;
};

MpiExtractCli parseExtract(int argc, char** argv) {
    Args args(argc, argv, 1);
    MpiExtractCli o;
    uint64_t cacheMb = 1024;
    while (!args.done()) {
        const std::string a = args.take();
        if (a == "--help" || a == "-h") {
            o.help = true;
            return o;
        } else if (a == "--iso") {
            o.iso = parseDouble(a, args.value(a));
        } else if (a == "--method") {
            const std::string m = args.value(a);
            if (m != "octree")
                throw UsageError("--method " + m + " is not yet under MPI (octree is); run it with vdiso");
        } else if (a == "-o" || a == "--output") {
            o.run.meshPath = args.value(a);
        } else if (a == "--mesh-space") {
            const std::string v = args.value(a);
            if (v != "physical" && v != "volume")
                throw UsageError("--mesh-space expects physical or volume, not '" + v + "'");
            o.run.physicalMeshes = v == "physical";
        } else if (a == "--stats") {
            o.statsPath = args.value(a);
        } else if (a == "--metacell") {
            o.run.metaCellSize = int(parseInt(a, args.value(a), 1, kMaxMetaCellSize));
        } else if (a == "--threads") {
            o.run.threads = int(parseInt(a, args.value(a), 1, 1024));
        } else if (a == "--cache-mb") {
            cacheMb = uint64_t(parseInt(a, args.value(a), 1, int64_t(1) << 30));
        } else if (a == "--force") {
            o.run.overwrite = true;
        } else if (a == "--quiet") {
            o.quiet = true;
        } else if (!a.empty() && a[0] == '-') {
            throw UsageError(a + " is not yet under MPI (or unknown); run it with vdiso extract");
        } else if (o.run.store.empty()) {
            o.run.store = a;
        } else {
            throw UsageError("unexpected argument '" + a + "'");
        }
    }
    if (o.run.store.empty()) throw UsageError("no store given");
    if (!o.iso) throw UsageError("--iso is required");
    o.run.iso = *o.iso;
    o.run.cacheBytes = cacheMb << 20;
    if (!o.run.meshPath.empty()) {
        MeshFormat format;
        try {
            format = meshFormatFor(o.run.meshPath);
        } catch (const std::exception& e) {
            throw UsageError(e.what());
        }
        if (format != MeshFormat::Ply)
            throw UsageError(o.run.meshPath + ": only .ply meshes are written under MPI for now");
    }
    return o;
}

int exitCodeOf(const std::exception& e) { return dynamic_cast<const UsageError*>(&e) ? 2 : 1; }

std::string statsJson(const MpiExtractCli& o, const mpi::RanksExtractResult& r) {
    JsonObject s;
    s.add("file", o.run.store).add("method", "octree").add("iso", o.run.iso);
    s.add("metacell", o.run.metaCellSize).add("threads", o.run.threads).add("ranks", r.ranks);
    s.add("level", 0).add("levels", r.levels);
    if (!o.run.meshPath.empty())
        s.add("mesh_space", o.run.physicalMeshes && r.hasOrientation ? "physical" : "volume");
    s.add("triangles", r.triangles).add("vertices", r.vertices);
    s.add("extract_s", r.seconds).add("read_method", r.readMethod);
    s.add("bricks_loaded", r.bricksLoaded).add("bricks_active", r.bricksActive);
    s.add("bytes_read", r.bytesRead).add("nodes_visited", r.nodesVisited);
    s.add("meta_cells_active", r.metaCellsActive).add("cells_active", r.cellsActive);
    s.add("partition_weight", "active sub-blocks");
    std::string perRank = "[";
    for (size_t k = 0; k < r.perRank.size(); ++k) {
        const mpi::RankExtractFigures& f = r.perRank[k];
        JsonObject p;
        p.add("rank", int64_t(k)).add("bricks", f.bricks).add("first_brick", f.firstBrick);
        p.add("last_brick", f.lastBrick).add("weight", f.weight);
        p.add("bricks_loaded", f.bricksLoaded).add("bytes_read", f.bytesRead);
        p.add("triangles", f.triangles).add("vertices_owned", f.verticesOwned);
        p.add("vertices_borrowed", f.verticesBorrowed);
        p.add("seconds", f.seconds).add("extract_s", f.extractSeconds);
        p.add("io_s", f.ioSeconds).add("decode_s", f.decodeSeconds);
        perRank += (k ? ", " : "") + p.str();
    }
    s.addRaw("per_rank", perRank + "]");
    s.add("peak_rss_mb_rank0", peakRssMb());
    return s.str();
}

int runExtract(const mpi::Communicator& comm, int argc, char** argv) {
    MpiExtractCli o;
    // Parsing: the same on every rank; existing outputs refused by rank 0 before any work.
    mpi::runPhase(comm, [&] {
        o = parseExtract(argc, argv);
        if (o.help || comm.rank() != 0) return;
        refuseExistingOutputs({&o.run.meshPath, &o.statsPath}, o.run.overwrite);
    }, exitCodeOf);
    if (o.help) {
        if (comm.rank() == 0) std::fputs(kExtractHelp, stdout);
        return 0;
    }
    const mpi::RanksExtractResult result = mpi::extractOctreeAcrossRanks(comm, o.run);
    mpi::runPhase(comm, [&] {
        if (comm.rank() != 0) return;
        const std::string text = statsJson(o, result) + "\n";
        if (o.statsPath == "-") {
            std::fputs(text.c_str(), stdout);
        } else if (!o.statsPath.empty()) {
            AtomicOutputFile out(o.statsPath, o.run.overwrite);
            out.append(text.data(), text.size());
            out.commit();
        }
        if (!o.quiet && o.statsPath != "-")
            std::printf("octree iso %g on %d ranks: %llu triangles, %llu vertices, %.3f s, %llu bricks read "
                        "(%.1f MB)\n",
                        o.run.iso, result.ranks, (unsigned long long)result.triangles,
                        (unsigned long long)result.vertices, result.seconds,
                        (unsigned long long)result.bricksLoaded, double(result.bytesRead) / 1e6);
    }, exitCodeOf);
    return 0;
}

}  // namespace

int main(int argc, char** argv) {
    mpi::MpiSession session(argc, argv);
    const mpi::Communicator comm;
    const bool printer = comm.rank() == 0;
    if (argc < 2 || !std::strcmp(argv[1], "--help") || !std::strcmp(argv[1], "-h")) {
        if (printer) std::fputs(kUsage, argc < 2 ? stderr : stdout);
        return argc < 2 ? 2 : 0;
    }
    const std::string command = argv[1];
    try {
        if (command == "extract") return runExtract(comm, argc - 1, argv + 1);
        if (printer) {
            if (command == "convert" || command == "synth" || command == "info" || command == "compare" ||
                command == "serve")
                std::fprintf(stderr, "vdiso-mpi: %s is not yet under MPI: run it with vdiso\n", command.c_str());
            else
                std::fprintf(stderr, "vdiso-mpi: unknown command '%s'\n\n%s", command.c_str(), kUsage);
        }
        return 2;
    } catch (const mpi::RankFailure& e) {
        if (printer) {
            if (e.exitCode() == 2)  // wrong usage: the same on every rank, so no rank to name
                std::fprintf(stderr, "vdiso-mpi %s: %s (see 'vdiso-mpi %s --help')\n", command.c_str(),
                             e.message().c_str(), command.c_str());
            else
                std::fprintf(stderr, "vdiso-mpi %s: %s\n", command.c_str(), e.what());
        }
        return e.exitCode();
    } catch (const std::exception& e) {
        // Not agreed on: reached by every rank alike (a collective call that failed everywhere).
        if (printer) std::fprintf(stderr, "vdiso-mpi %s: rank %d: %s\n", command.c_str(), comm.rank(), e.what());
        return 1;
    }
}
