#include <algorithm>
#include <cstdio>
#include <optional>
#include <string>

#include "app/extract_session.h"
#include "app/frame_files.h"
#include "cli/args.h"
#include "cli/extract_options.h"
#include "cli/progress_bar.h"
#include "core/camera.h"
#include "core/view_presets.h"
#include "io/atomic_output.h"
#include "io/json.h"
#include "io/mesh/mesh_writer.h"
#include "io/process_stats.h"
#include "io/render/oracle_comparison.h"
#include "tools/commands.h"

namespace vdiso::cli {

namespace {

// "frame_%04d.png" with frame k; refuses names without exactly one integer conversion.
std::string framePath(const std::string& pattern, int frame) {
    char buffer[4096];
    std::snprintf(buffer, sizeof buffer, pattern.c_str(), frame);
    return buffer;
}

// One extraction from one camera (or none, for the full methods without a picture), with its
// outputs; returns its statistics.
JsonObject extractFrame(const ExtractOptions& o, ExtractSession& session, const std::optional<Camera>& camera,
                        const std::string& meshPath, const std::string& pngPath, const std::string& pointsPath,
                        const ProgressFn& progress, std::string& summary) {
    // Without a picture to draw, the mesh goes to its file as it is extracted: memory holds a
    // bounded part of it. A picture needs the whole mesh, so then it is held.
    const SpaceTransform meshTransform = session.meshTransform();
    std::optional<MeshFileWriter> streamed;
    if (!meshPath.empty() && pngPath.empty() && !isViewDependent(o.method))
        streamed.emplace(meshPath, o.overwrite, o.meshCompress, meshTransform);
    FrameOutput output;
    if (streamed) output.sink = &*streamed;
    output.postBeside = meshPath.empty() ? pngPath : meshPath;
    output.postProgress = progressBar("post-process", 0, o.quiet);
    ExtractFrame frame = session.extract(camera, output, progress);
    const ExtractStats& stats = frame.stats;
    if (frame.post && frame.post->pieces > 0 && frame.post->piecesKept == 0)
        std::fprintf(stderr,
                     "vdiso extract: warning: --min-piece %llu dropped every piece (the largest has %llu "
                     "triangles): the mesh is empty\n",
                     (unsigned long long)o.post.minPieceTriangles,
                     (unsigned long long)frame.post->largestPieceTriangles);

    if (streamed) streamed->finish();
    // The held mesh's file (a streamed one is written already), the points and the picture.
    const FrameFiles files{streamed ? std::string() : meshPath, pointsPath, pngPath, o.overwrite, o.meshCompress};
    const std::optional<double> drawSeconds =
        writeFrameFiles(files, frame.mesh, frame.points, camera ? &*camera : nullptr, meshTransform);

    JsonObject s = session.frameStats(frame, !meshPath.empty() || !pointsPath.empty());
    if (drawSeconds) s.add("draw_s", *drawSeconds);
    if (o.oracle && camera) {
        // After this frame's figures are taken: the full surface from the same camera.
        const OracleComparison c =
            compareWithOracle(session.cache(), *camera, *o.iso, o.metaCellSize, frame.plan.threads);
        const VisibleSurfaceOracle& v = c.oracle;
        s.add("oracle_pixels", v.pixels).add("oracle_cells", v.cells);
        s.add("oracle_triangles", v.triangles).add("oracle_bricks", v.bricks);
        s.add("full_triangles", c.fullTriangles);
        s.add("triangles_over_oracle", double(stats.triangles) / double(std::max<uint64_t>(1, v.triangles)));
        s.add("bricks_over_oracle", double(frame.io.misses) / double(std::max<uint64_t>(1, v.bricks)));
        s.add("primitives_per_pixel",
              double(stats.triangles + frame.points.size()) / double(std::max<uint64_t>(1, v.pixels)));
    }
    s.add("peak_rss_mb", peakRssMb());
    char line[512];
    std::snprintf(line, sizeof line,
                  "%s iso %g: %llu triangles, %zu points, %.3f s extract (%.3f s read, %.3f s "
                  "decode), %llu bricks read (%.1f MB)%s",
                  o.method.c_str(), *o.iso, (unsigned long long)stats.triangles, frame.points.size(),
                  stats.extractSeconds, frame.io.readSeconds, frame.io.decodeSeconds,
                  (unsigned long long)frame.io.misses, frame.io.bytesRead / 1e6,
                  drawSeconds ? (", drawn in " + std::to_string(*drawSeconds) + " s").c_str() : "");
    summary = line;
    session.recycle(std::move(frame));  // the next frame of a path fills the same arrays
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
    ExtractSession session(store, o);
    const VolumeInfo& volume = store.volume();
    ViewChoice view;
    const std::vector<Camera> cameras = extractCameras(o, volume, view);
    const bool path = o.orbitFrames > 0 || !o.pathFile.empty();

    std::string statsText, summary;
    const ProgressFn progress = progressBar("extract", 0, o.quiet || path);
    const size_t frames = std::max<size_t>(1, cameras.size());
    for (size_t f = 0; f < frames; ++f) {
        const std::optional<Camera> camera =
            cameras.empty() ? std::nullopt : std::optional<Camera>(cameras[f]);
        const std::string png = path && !o.pngPath.empty() ? framePath(o.pngPath, int(f)) : o.pngPath;
        JsonObject s = extractFrame(o, session, camera, path ? "" : o.meshPath, png, path ? "" : o.pointsPath,
                                    progress, summary);
        // Built before the first frame, outside its extract_s; shared by the frames of a path.
        if (isViewDependent(o.method) && f == 0) s.add("tree_s", session.treeSeconds());
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
