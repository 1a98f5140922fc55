#include <algorithm>
#include <chrono>
#include <cstdio>
#include <optional>
#include <string>

#include "cache/brick_cache.h"
#include "cache/cache_plan.h"
#include "core/camera.h"
#include "core/extract_full.h"
#include "core/extract_view.h"
#include "core/level_source.h"
#include "io/atomic_output.h"
#include "io/json.h"
#include "io/mesh_post.h"
#include "io/mesh_writer.h"
#include "io/oracle_comparison.h"
#include "io/png_image.h"
#include "io/process_stats.h"
#include "io/renderer.h"
#include "tools/args.h"
#include "tools/commands.h"
#include "tools/extract_options.h"
#include "tools/extract_stats_json.h"
#include "tools/progress_bar.h"

namespace vdiso::cli {

namespace {

// "frame_%04d.png" with frame k; refuses names without exactly one integer conversion.
std::string framePath(const std::string& pattern, int frame) {
    char buffer[4096];
    std::snprintf(buffer, sizeof buffer, pattern.c_str(), frame);
    return buffer;
}

// One extraction from one camera (or none, for the full methods without a picture), with its
// outputs; returns its statistics. `before`: the cache's counters before this frame, so a
// frame's I/O figures are its own while the cache is kept across frames.
JsonObject extractFrame(const ExtractOptions& o, const BrickStoreReader& store, BrickCache& cache,
                        const std::optional<Camera>& camera, const std::string& meshPath,
                        const std::string& pngPath, const std::string& pointsPath,
                        MetaCellRangeCache& ranges, const MinMaxTree* tree, const ProgressFn& progress,
                        std::string& summary) {
    const CacheCounters before = cache.counters();
    const CachePlan plan = planCache(o, cache, machineThreads());
    // Without a picture to draw, the mesh goes to its file as it is extracted: memory holds a
    // bounded part of it. A picture needs the whole mesh, so then it is held.
    TriangleMesh mesh;
    // Meshes are extracted in volume space and written in physical space (unless asked not to).
    const SpaceTransform meshTransform =
        o.physicalMeshes.value_or(true) ? volumeToPhysical(store.volume()) : SpaceTransform{};
    std::optional<MeshFileWriter> streamed;
    if (!meshPath.empty() && pngPath.empty() && !isViewDependent(o.method))
        streamed.emplace(meshPath, o.overwrite, o.meshCompress, meshTransform);
    PointSet points;
    ExtractStats stats;
    std::optional<MeshPostStats> post;
    if (isViewDependent(o.method)) {
        ViewExtractOptions v = viewExtractOptions(o, plan);
        v.rangeCache = &ranges;
        v.tree = tree;
        stats = extractViewDependent(cache, *camera, v, mesh, points, progress);
    } else {
        FullExtractOptions extract{*o.iso, o.metaCellSize, plan.threads};
        extract.prefetchBricks = plan.prefetchBricks;
        extract.prefetchReaders = o.readers;
        LevelSource level(cache, o.level);
        // Post-processing takes the surface brick by brick and hands its result on to the file
        // (streamed) or to the mesh held for the picture.
        MeshAppender held(mesh);
        std::optional<PostProcessedMesh> postProcess;
        if (o.post.any()) {
            MeshPostOptions shape = o.post;
            shape.threads = plan.threads;
            postProcess.emplace(meshPath.empty() ? pngPath : meshPath, level.layout(), shape,
                                streamed ? static_cast<MeshSink&>(*streamed) : held);
            extract.brickSink = &*postProcess;
        } else if (streamed) {
            extract.sink = &*streamed;
        }
        // Brick by brick, the extraction's own mesh is a passing buffer, not the one held.
        TriangleMesh passing;
        TriangleMesh& into = postProcess ? passing : mesh;
        stats = o.method == "noise" ? extractNoise(level, extract, into, progress)
                                    : extractOctree(level, extract, into, progress);
        if (postProcess) {
            post = postProcess->finish(progressBar("post-process", 0, o.quiet));
            if (post->pieces > 0 && post->piecesKept == 0)
                std::fprintf(stderr,
                             "vdiso extract: warning: --min-piece %llu dropped every piece (the largest has %llu "
                             "triangles): the mesh is empty\n",
                             (unsigned long long)o.post.minPieceTriangles,
                             (unsigned long long)post->largestPieceTriangles);
            stats.triangles = post->trianglesOut;
            stats.vertices = post->verticesOut;
        }
    }
    const CacheCounters io = cache.counters() - before;

    if (streamed)
        streamed->finish();
    else if (!meshPath.empty())
        writeMesh(meshPath, mesh, o.overwrite, o.meshCompress, meshTransform);
    std::optional<double> drawSeconds;
    if (!pointsPath.empty()) writePointsPly(pointsPath, points, o.overwrite, meshTransform);
    if (!pngPath.empty()) {
        const RenderResult r = renderSurface(mesh, points, *camera);
        writePng(pngPath, r.image, o.overwrite);
        drawSeconds = r.drawSeconds;
    }

    const VolumeInfo& volume = store.volume();
    JsonObject s;
    s.add("file", store.path()).add("method", o.method).add("iso", *o.iso);
    s.add("metacell", o.metaCellSize).add("threads", plan.threads);
    if (isViewDependent(o.method))
        s.add("lod_error", o.lodError).add("coarse_bricks", stats.view.coarseBricks)
            .add("capped_faces", stats.view.cappedFaces);
    else
        s.add("level", o.level);
    s.add("levels", store.header().levelCount);
    if (!meshPath.empty() || !pointsPath.empty())
        s.add("mesh_space", o.physicalMeshes.value_or(true) && volume.hasOrientation ? "physical" : "volume");
    s.add("triangles", stats.triangles).add("points", uint64_t(points.size()));
    s.add("vertices", stats.vertices).add("mesh_streamed", bool(streamed));
    if (post) {
        s.add("smooth", o.post.smoothIterations).add("decimate", o.post.decimateRatio);
        s.add("largest", o.post.largestPiece).add("min_piece", o.post.minPieceTriangles);
        s.add("triangles_extracted", post->trianglesIn).add("vertices_extracted", post->verticesIn);
        s.add("pieces", post->pieces).add("pieces_kept", post->piecesKept);
        s.add("largest_piece_triangles", post->largestPieceTriangles);
        s.add("post_slabs", post->slabs).add("post_halo_slabs", post->haloSlabs);
        s.add("post_window_triangles_max", post->largestWindowTriangles);
        s.add("post_spool_mb", double(post->spoolBytes) / 1e6);
        s.add("pieces_s", post->piecesSeconds).add("post_s", post->finishSeconds);
    }
    s.add("extract_s", stats.extractSeconds).add("preprocess_s", stats.preprocessSeconds);
    s.add("io_s", io.readSeconds).add("decode_s", io.decodeSeconds);
    s.add("read_method", store.readMethod());
    // A remote store: every request sent (the open's, the index's, retries) and the bytes they
    // brought, from the open on.
    if (const RemoteFile* remote = store.remote()) {
        s.add("remote_requests", remote->requests()).add("remote_bytes", remote->bytesFetched());
        s.add("disk_cache_hits", remote->diskCacheHits()).add("disk_cache_bytes", remote->diskCacheBytes());
    }
    s.add("prefetch", plan.threads > 1 && !isViewDependent(o.method) ? 0 : plan.prefetchBricks);
    s.add("readers", o.readers);
    // I/O the extraction did not wait for: read and decode time spent ahead of it (summed over
    // the reader threads, as io_s and decode_s are). With image strips a lower bound: a strip
    // waiting for a brick another strip loads counts as waiting, the read only once.
    s.add("brick_wait_s", stats.brickWaitSeconds);
    s.add("io_hidden_s", std::max(0.0, io.readSeconds + io.decodeSeconds - stats.brickWaitSeconds));
    s.add("bricks_loaded", io.misses).add("bricks_requested", io.requests);
    s.add("bricks_active", stats.bricksActive).add("bytes_read", io.bytesRead);
    s.add("nodes_visited", stats.nodesVisited).add("meta_cells_active", stats.metaCellsActive);
    s.add("cells_active", stats.cellsActive);
    if (isViewDependent(o.method)) addViewCounters(s, stats);
    s.add("voxels_per_s", double(volume.sampleCount()) / stats.extractSeconds);
    if (drawSeconds) s.add("draw_s", *drawSeconds);
    if (o.oracle && camera) {
        // After this frame's figures are taken: the full surface from the same camera.
        const OracleComparison c = compareWithOracle(cache, *camera, *o.iso, o.metaCellSize, plan.threads);
        const VisibleSurfaceOracle& v = c.oracle;
        s.add("oracle_pixels", v.pixels).add("oracle_cells", v.cells);
        s.add("oracle_triangles", v.triangles).add("oracle_bricks", v.bricks);
        s.add("full_triangles", c.fullTriangles);
        s.add("triangles_over_oracle", double(stats.triangles) / double(std::max<uint64_t>(1, v.triangles)));
        s.add("bricks_over_oracle", double(io.misses) / double(std::max<uint64_t>(1, v.bricks)));
        s.add("primitives_per_pixel",
              double(stats.triangles + points.size()) / double(std::max<uint64_t>(1, v.pixels)));
    }
    s.add("peak_rss_mb", peakRssMb());
    char line[512];
    std::snprintf(line, sizeof line,
                  "%s iso %g: %llu triangles, %zu points, %.3f s extract (%.3f s read, %.3f s "
                  "decode), %llu bricks read (%.1f MB)%s",
                  o.method.c_str(), *o.iso, (unsigned long long)stats.triangles, points.size(),
                  stats.extractSeconds, io.readSeconds, io.decodeSeconds,
                  (unsigned long long)io.misses, io.bytesRead / 1e6,
                  drawSeconds ? (", drawn in " + std::to_string(*drawSeconds) + " s").c_str() : "");
    summary = line;
    return s;
}

}  // namespace

int runExtract(int argc, char** argv) {
    ExtractOptions o = parseExtractOptions(argc, argv);
    if (o.help) {
        std::fputs(kExtractHelp, stdout);
        std::fputs(kRemoteOptionsHelp, stdout);
        return 0;
    }
    // Existing outputs are refused before the work starts, not after minutes of extraction.
    refuseExistingOutputs({&o.meshPath, &o.pngPath, &o.statsPath, &o.pointsPath}, o.overwrite);

    const BrickStoreReader store(o.input, StoreOpenOptions{o.cold ? ReadMode::Cold : ReadMode::Buffered, o.remote});
    if (store.remote()) adaptToRemoteStore(o);
    BrickCache cache(store, o.cacheMb << 20);
    if (o.level >= store.header().levelCount)
        throw UsageError("--level " + std::to_string(o.level) + ": " + o.input + " holds " +
                         std::to_string(store.header().levelCount) + " level" +
                         (store.header().levelCount == 1 ? "" : "s") + " of detail (0 to " +
                         std::to_string(store.header().levelCount - 1) + ")");
    const VolumeInfo& volume = store.volume();
    ViewChoice view;
    const std::vector<Camera> cameras = extractCameras(o, volume, view);
    const bool path = o.orbitFrames > 0 || !o.pathFile.empty();

    // Meta-cell ranges are kept across the frames of a path, for as many bricks as the cache.
    MetaCellRangeCache ranges(cache.budgetBytes() / store.brickBytes());
    // The view-dependent methods' tree, likewise built once.
    std::optional<MinMaxTree> tree;
    const auto treeStart = std::chrono::steady_clock::now();
    if (isViewDependent(o.method)) tree.emplace(cache.levels(), cache.brickRanges());
    const double treeSeconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - treeStart).count();
    std::string statsText, summary;
    const ProgressFn progress = progressBar("extract", 0, o.quiet || path);
    const size_t frames = std::max<size_t>(1, cameras.size());
    for (size_t f = 0; f < frames; ++f) {
        const std::optional<Camera> camera =
            cameras.empty() ? std::nullopt : std::optional<Camera>(cameras[f]);
        const std::string png = path && !o.pngPath.empty() ? framePath(o.pngPath, int(f)) : o.pngPath;
        JsonObject s = extractFrame(o, store, cache, camera, path ? "" : o.meshPath, png,
                                    path ? "" : o.pointsPath, ranges, tree ? &*tree : nullptr, progress, summary);
        // Built before the first frame, outside its extract_s; shared by the frames of a path.
        if (tree && f == 0) s.add("tree_s", treeSeconds);
        if (path) s.add("frame", int64_t(f));
        else if (camera)
            s.add("view", o.cameraPath.empty() ? viewChoiceName(view) : o.cameraPath);
        statsText += s.str() + "\n";
        if (o.statsPath == "-") std::fputs((s.str() + "\n").c_str(), stdout);
        if (!o.quiet && o.statsPath != "-")
            std::printf("%s%s\n", path ? ("frame " + std::to_string(f) + ": ").c_str() : "",
                        summary.c_str());
    }
    if (!o.statsPath.empty() && o.statsPath != "-") {
        AtomicOutputFile out(o.statsPath, o.overwrite);
        out.append(statsText.data(), statsText.size());
        out.commit();
    }
    return 0;
}

}  // namespace vdiso::cli
