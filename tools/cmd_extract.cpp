#include <algorithm>
#include <cctype>
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
#include "io/camera_json.h"
#include "io/json.h"
#include "io/mesh_post.h"
#include "io/mesh_writer.h"
#include "io/oracle_comparison.h"
#include "io/png_image.h"
#include "io/process_stats.h"
#include "io/renderer.h"
#include "tools/args.h"
#include "tools/commands.h"
#include "tools/progress_bar.h"

namespace vdiso::cli {

namespace {

constexpr const char* kHelp =
    "usage: vdiso extract FILE.vdiso --iso V [options]\n"
    "\n"
    "Extracts the isosurface at V from a brick store, reading only the bricks that can hold\n"
    "it, and writes the mesh, a picture and statistics.\n"
    "\n"
    "  --iso V                   isovalue (a sample is above the surface when > V)\n"
    "  --method octree|noise|sage|wise\n"
    "                            octree: min/max tree over bricks, then meta-cells (default);\n"
    "                            noise: span space over all meta-cells (reads every brick once\n"
    "                            to build it, reported as preprocess_s);\n"
    "                            sage: only what the camera sees (view-dependent, SAGE);\n"
    "                            wise: the same with WISE's choices (the switches below off)\n"
    "  --scan polygons|triangles     sage/wise: scan-convert whole polygons or each triangle\n"
    "  --box estimate|exact          sage/wise: screen box by the SAGE estimate or 8 corners\n"
    "  --points on|off               sage/wise: sub-pixel parts as points\n"
    "  --update bottom-up|top-down   sage/wise: occlusion pyramid update\n"
    "  --cell-test on|off        sage/wise: test each cell of an extracted meta-cell too,\n"
    "                            and keep a cell only if it covers a new pixel centre\n"
    "                            (on for sage, off for wise)\n"
    "  --lod-error P             sage/wise: extract each part of the volume at the coarsest\n"
    "                            level of detail whose cells span at most P pixels on screen\n"
    "                            (default 1; 0: full resolution only). Stores converted with\n"
    "                            --levels 0 (or before format 3) have full resolution only\n"
    "  --seams cap|open          sage/wise: close each brick's surface on faces that meet\n"
    "                            another level of detail, so no crack shows (default cap)\n"
    "  --level L                 octree/noise: extract the whole surface at level of detail L\n"
    "                            (cells 2^L times larger: a quick coarse mesh; default 0)\n"
    "  --occlusion on|off        sage/wise: occlusion culling (default on); off draws all that\n"
    "                            is in view, front and back, to measure what culling saves\n"
    "  --points-out POINTS.ply   write the points (with normals)\n"
    "  --oracle                  also measure the visible-surface oracle: the full surface's\n"
    "                            depth buffer mapped back to cells and bricks, the least any\n"
    "                            view-dependent extraction must produce and read; reports\n"
    "                            oracle_* figures and our ratios to them\n"
    "  --path orbit:N | CAMS.json    a moving camera: N frames around the volume (from the\n"
    "                            --view preset), or a JSON list of cameras; one cache is kept\n"
    "                            across frames; --stats gets one JSON line per frame, --png\n"
    "                            a pattern (frame_%04d.png)\n"
    "  -o, --output MESH         write the mesh, in the format its extension names: .ply\n"
    "                            (binary, normals), .obj, .stl (binary), .glb (glTF 2.0\n"
    "                            binary, normals) or .vtp (VTK XML PolyData, for ParaView)\n"
    "  --mesh-space physical|volume\n"
    "                            the space meshes (-o, --points-out) are written in. physical\n"
    "                            (default): the patient's LPS coordinates (in the input's\n"
    "                            units, mm for DICOM), where the\n"
    "                            input's orientation put the volume (DICOM, NIfTI, NRRD,\n"
    "                            MetaImage), as 3D Slicer (4.11 on) and ITK place models;\n"
    "                            volume: origin + index * spacing, axis-aligned, the space\n"
    "                            vdiso extracts and renders in (before store format 4, vdiso\n"
    "                            wrote this with a RAS input's origin as RAS; it is LPS now).\n"
    "                            The two are the same for a store without\n"
    "                            orientation (vdiso info says whether it has one)\n"
    "  --mesh-compress           .glb: compress the mesh with meshoptimizer\n"
    "                            (EXT_meshopt_compression; three.js loads it with its\n"
    "                            MeshoptDecoder)\n"
    "  --smooth N                octree/noise: N iterations of Taubin smoothing (lambda|mu:\n"
    "                            no shrinkage), on surfaces larger than memory: bricks are\n"
    "                            spooled beside the output and smoothed a layer at a time\n"
    "                            with the layers N cells reach, which gives the result of\n"
    "                            smoothing the whole mesh at once; normals from the smoothed\n"
    "                            surface\n"
    "  --decimate R              octree/noise: keep a fraction R (0 < R <= 1) of the triangles\n"
    "                            (meshoptimizer's simplifier, each layer of bricks on its own\n"
    "                            with its borders locked, so layers still meet exactly)\n"
    "  --largest                 octree/noise: keep only the largest connected piece\n"
    "  --min-piece N             octree/noise: drop connected pieces of fewer than N triangles\n"
    "                            (pieces are found across bricks by union-find)\n"
    "  --png IMAGE.png           render the mesh with OSMesa and write a picture\n"
    "  --view DISTANCE|SIDE|DISTANCE,SIDE\n"
    "                            camera preset framed from the volume: the picture's camera,\n"
    "                            and the extraction's for sage/wise. DISTANCE: distant, normal\n"
    "                            (default) or closeup. SIDE, for a store with orientation: the\n"
    "                            side of the patient the camera looks at, anterior (default:\n"
    "                            a head's face, upright), posterior, left, right (superior up),\n"
    "                            superior or inferior (anterior up); e.g. --view left,\n"
    "                            --view closeup,anterior. A store without orientation is seen\n"
    "                            from the front (+y), a little from the side and above, +z up.\n"
    "                            (A mirrored grid, e.g. stored radiologically, is drawn in\n"
    "                            volume space: left and right swap; up stays up.)\n"
    "  --camera CAM.json         camera from a file: {\"eye\":[..],\"target\":[..],\"up\":[..],\n"
    "                            \"fov\":30,\"width\":800,\"height\":600}\n"
    "  --size WxH                image size (default 800x800)\n"
    "  --stats STATS.json        write one JSON object of statistics ('-' for stdout)\n"
    "  --metacell M              meta-cell size in cells, 1 to 32 (default 4)\n"
    "  --threads N               extraction threads (default: the machine's cores); sage and\n"
    "                            wise split the image into N vertical strips, one traversal each\n"
    "  --prefetch N              bricks a reader thread loads ahead of the extraction\n"
    "                            (default 32; 0: none): for sage/wise those a look-ahead finds\n"
    "                            visible; for octree/noise the active bricks, with --threads 1\n"
    "                            (with more threads no reader thread runs: stats say prefetch 0)\n"
    "  --readers N               threads reading those bricks, so N reads wait on the disk at\n"
    "                            once (default 2)\n"
    "  --cache-mb N              brick cache budget in MB (default 1024)\n"
    "  --cold                    drop the store's pages from the page cache first and read\n"
    "                            every brick from disk (O_DIRECT), so io_s is disk time\n"
    "  --force                   replace existing output files\n"
    "  --quiet                   no progress bar or summary\n";

struct ExtractOptions {
    std::string input;
    std::optional<bool> scanPolygons, estimateBox, points, bottomUp, cellTests, occlusion, capSeams;  // sage/wise
    std::string pointsPath;
    bool oracle = false;
    int orbitFrames = 0;   // --path orbit:N
    std::string pathFile;  // --path FILE.json
    std::optional<double> iso;
    double lodError = 1.0;
    bool lodErrorGiven = false;
    int level = 0;
    std::string method = "octree";
    std::string meshPath, pngPath, statsPath, cameraPath;
    ViewChoice view;
    bool viewGiven = false;
    std::optional<bool> physicalMeshes;  // --mesh-space; default physical
    int width = 800, height = 800;
    int metaCellSize = kDefaultMetaCellSize;
    int threads = 0;  // 0: the machine's cores (as many as the cache allows strips for)
    int prefetch = 32;
    int readers = BrickPrefetcher::kDefaultReaders;
    uint64_t cacheMb = 1024;
    bool overwrite = false, quiet = false, cold = false;
    bool meshCompress = false;  // --mesh-compress (.glb only)
    MeshPostOptions post;       // --smooth, --decimate, --largest, --min-piece
};

void parseSize(const std::string& text, int& width, int& height) {
    const size_t x = text.find('x');
    if (x == std::string::npos) throw UsageError("--size expects WxH, not '" + text + "'");
    width = int(parseInt("--size", text.substr(0, x), 16, 8192));
    height = int(parseInt("--size", text.substr(x + 1), 16, 8192));
}

// True for a name with exactly one integer conversion (frame_%04d.png).
bool isFramePattern(const std::string& pattern) {
    size_t conversions = 0;
    for (size_t i = 0; i < pattern.size(); ++i) {
        if (pattern[i] != '%') continue;
        if (i + 1 < pattern.size() && pattern[i + 1] == '%') {
            ++i;
            continue;
        }
        size_t j = i + 1;
        while (j < pattern.size() && (std::isdigit(static_cast<unsigned char>(pattern[j])))) ++j;
        if (j >= pattern.size() || pattern[j] != 'd') return false;
        ++conversions;
        i = j;
    }
    return conversions == 1;
}

bool parseSwitch(const std::string& flag, const std::string& value, const char* on, const char* off) {
    if (value == on) return true;
    if (value == off) return false;
    throw UsageError(flag + " expects " + on + " or " + off + ", not '" + value + "'");
}

bool isViewDependent(const std::string& method) { return method == "sage" || method == "wise"; }

ExtractOptions parseExtractOptions(int argc, char** argv, bool& helpShown) {
    Args args(argc, argv, 1);
    ExtractOptions o;
    while (!args.done()) {
        const std::string a = args.take();
        if (a == "--help" || a == "-h") {
            std::fputs(kHelp, stdout);
            helpShown = true;
            return o;
        } else if (a == "--iso") {
            o.iso = parseDouble(a, args.value(a));
        } else if (a == "--method") {
            o.method = args.value(a);
            if (o.method != "octree" && o.method != "noise" && o.method != "sage" && o.method != "wise")
                throw UsageError("--method expects octree, noise, sage or wise, not '" + o.method + "'");
        } else if (a == "--lod-error") {
            o.lodError = parseDouble(a, args.value(a));
            if (!(o.lodError >= 0 && o.lodError <= 1e6))
                throw UsageError("--lod-error expects pixels, 0 or more, not " + std::to_string(o.lodError));
            o.lodErrorGiven = true;
        } else if (a == "--level") {
            o.level = int(parseInt(a, args.value(a), 0, kMaxLevels - 1));
        } else if (a == "--scan") {
            o.scanPolygons = parseSwitch(a, args.value(a), "polygons", "triangles");
        } else if (a == "--box") {
            o.estimateBox = parseSwitch(a, args.value(a), "estimate", "exact");
        } else if (a == "--points") {
            o.points = parseSwitch(a, args.value(a), "on", "off");
        } else if (a == "--update") {
            o.bottomUp = parseSwitch(a, args.value(a), "bottom-up", "top-down");
        } else if (a == "--oracle") {
            o.oracle = true;
        } else if (a == "--path") {
            const std::string p = args.value(a);
            if (p.rfind("orbit:", 0) == 0)
                o.orbitFrames = int(parseInt(a, p.substr(6), 1, 100000));
            else
                o.pathFile = p;
        } else if (a == "--seams") {
            o.capSeams = parseSwitch(a, args.value(a), "cap", "open");
        } else if (a == "--occlusion") {
            o.occlusion = parseSwitch(a, args.value(a), "on", "off");
        } else if (a == "--cell-test") {
            o.cellTests = parseSwitch(a, args.value(a), "on", "off");
        } else if (a == "--points-out") {
            o.pointsPath = args.value(a);
        } else if (a == "-o" || a == "--output") {
            o.meshPath = args.value(a);
        } else if (a == "--mesh-space") {
            o.physicalMeshes = parseSwitch(a, args.value(a), "physical", "volume");
        } else if (a == "--mesh-compress") {
            o.meshCompress = true;
        } else if (a == "--smooth") {
            o.post.smoothIterations = int(parseInt(a, args.value(a), 0, 1000));
        } else if (a == "--decimate") {
            const std::string ratio = args.value(a);
            o.post.decimateRatio = parseDouble(a, ratio);
            if (!(o.post.decimateRatio > 0 && o.post.decimateRatio <= 1))
                throw UsageError("--decimate expects the fraction of triangles to keep, above 0 and at "
                                 "most 1, not " + ratio);
        } else if (a == "--largest") {
            o.post.largestPiece = true;
        } else if (a == "--min-piece") {
            o.post.minPieceTriangles = uint64_t(parseInt(a, args.value(a), 1, int64_t(1) << 40));
        } else if (a == "--png") {
            o.pngPath = args.value(a);
        } else if (a == "--view") {
            const std::string v = args.value(a);
            try {
                o.view = parseViewChoice(v);
            } catch (const std::invalid_argument& e) {
                throw UsageError(e.what());
            }
            o.viewGiven = true;
        } else if (a == "--camera") {
            o.cameraPath = args.value(a);
        } else if (a == "--size") {
            parseSize(args.value(a), o.width, o.height);
        } else if (a == "--stats") {
            o.statsPath = args.value(a);
        } else if (a == "--metacell") {
            o.metaCellSize = int(parseInt(a, args.value(a), 1, kMaxMetaCellSize));
        } else if (a == "--threads") {
            o.threads = int(parseInt(a, args.value(a), 1, 256));
        } else if (a == "--prefetch") {
            o.prefetch = int(parseInt(a, args.value(a), 0, 4096));
        } else if (a == "--readers") {
            o.readers = int(parseInt(a, args.value(a), 1, 16));
        } else if (a == "--cache-mb") {
            o.cacheMb = uint64_t(parseInt(a, args.value(a), 1, int64_t(1) << 30));
        } else if (a == "--cold") {
            o.cold = true;
        } else if (a == "--force") {
            o.overwrite = true;
        } else if (a == "--quiet") {
            o.quiet = true;
        } else if (!a.empty() && a[0] == '-') {
            throw UsageError("unknown option '" + a + "'");
        } else if (o.input.empty()) {
            o.input = a;
        } else {
            throw UsageError("expects one FILE");
        }
    }
    if (o.input.empty()) throw UsageError("expects FILE.vdiso");
    if (!o.iso) throw UsageError("needs --iso V");
    if (o.viewGiven && !o.cameraPath.empty()) throw UsageError("give --view or --camera, not both");
    const bool viewDependent = isViewDependent(o.method);
    if (o.pngPath.empty() && !viewDependent && o.orbitFrames == 0 && o.pathFile.empty() &&
        (o.viewGiven || !o.cameraPath.empty()))
        throw UsageError("--view and --camera frame the picture: they need --png (or a "
                         "view-dependent --method)");
    if (!viewDependent && (o.scanPolygons || o.estimateBox || o.points || o.bottomUp || o.cellTests || o.occlusion ||
                            o.capSeams))
        throw UsageError("--scan, --box, --points, --update, --cell-test, --occlusion and --seams apply to "
                         "--method sage or wise");
    if (o.lodErrorGiven && !viewDependent)
        throw UsageError("--lod-error applies to --method sage or wise; the full methods take one "
                         "--level for the whole surface");
    if (o.level != 0 && viewDependent)
        throw UsageError("--level applies to --method octree or noise; sage and wise choose a "
                         "level per part of the volume by --lod-error");
    if (o.post.any() && viewDependent)
        throw UsageError("--smooth, --decimate, --largest and --min-piece apply to the full surface: "
                         "--method octree or noise");
    if (o.post.any() && o.meshPath.empty() && o.pngPath.empty())
        throw UsageError("--smooth, --decimate, --largest and --min-piece shape the mesh: give -o MESH "
                         "or --png");
    if (!o.pointsPath.empty() && !viewDependent)
        throw UsageError("--points-out needs --method sage or wise (only they make points)");
    if (!o.meshPath.empty()) meshFormatFor(o.meshPath);  // an unknown extension fails before work
    if (o.physicalMeshes && o.meshPath.empty() && o.pointsPath.empty())
        throw UsageError("--mesh-space applies to mesh outputs (-o MESH, --points-out POINTS.ply)");
    if (o.meshCompress && (o.meshPath.empty() || meshFormatFor(o.meshPath) != MeshFormat::Glb))
        throw UsageError("--mesh-compress applies to a .glb mesh output (-o MESH.glb)");
    if (o.oracle && !viewDependent && o.pngPath.empty() && !o.viewGiven && o.cameraPath.empty())
        throw UsageError("--oracle needs a camera: --view, --camera or a view-dependent --method");
    if (o.orbitFrames > 0 || !o.pathFile.empty()) {
        if (o.oracle) throw UsageError("--oracle measures one view, not a --path");
        if (!o.cameraPath.empty()) throw UsageError("give --path or --camera, not both");
        if (!o.meshPath.empty() || !o.pointsPath.empty() || o.post.any())
            throw UsageError("a --path writes pictures (--png frame_%04d.png) and statistics, "
                             "not meshes (nor post-processes them)");
        if (!o.pngPath.empty() && !isFramePattern(o.pngPath))
            throw UsageError("with --path, --png needs one %d in its name (frame_%04d.png)");
        if (!isViewDependent(o.method) && o.pngPath.empty())
            throw UsageError("a --path with a full method extracts the same surface each "
                             "frame: use --method sage or wise, or ask for --png pictures");
    }
    return o;
}

}  // namespace

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
    CachePlan plan;
    try {
        plan = planCacheUse(cache, isViewDependent(o.method), o.prefetch, o.threads, machineThreads());
    } catch (const std::invalid_argument& e) {
        throw UsageError(e.what() + std::string(" (--cache-mb ") + std::to_string(o.cacheMb) + ")");
    }
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
        ViewExtractOptions v = o.method == "sage" ? ViewExtractOptions::sage(*o.iso)
                                                  : ViewExtractOptions::wise(*o.iso);
        v.metaCellSize = o.metaCellSize;
        if (o.scanPolygons) v.scanPolygons = *o.scanPolygons;
        if (o.estimateBox) v.estimateBox = *o.estimateBox;
        if (o.points) v.points = *o.points;
        if (o.bottomUp) v.bottomUp = *o.bottomUp;
        if (o.cellTests) v.cellTests = *o.cellTests;
        if (o.occlusion) v.occlusion = *o.occlusion;
        if (o.capSeams) v.capSeams = *o.capSeams;
        v.prefetchBricks = plan.prefetchBricks;
        v.prefetchReaders = o.readers;
        v.threads = plan.threads;
        v.rangeCache = &ranges;
        v.tree = tree;
        v.lodError = o.lodError;
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
    s.add("file", o.input).add("method", o.method).add("iso", *o.iso);
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
    if (isViewDependent(o.method)) {
        const ViewCounters& view = stats.view;
        s.add("culled_range", view.culledByRange).add("culled_frustum", view.culledByFrustum);
        s.add("culled_occlusion", view.culledByOcclusion);
        s.add("dropped_subpixel", view.droppedSubPixel);
        s.add("meta_cells_extracted", stats.metaCellsActive).add("scan_s", view.scanSeconds);
        s.add("cells_culled", view.cellsCulled);
        s.add("bricks_prefetched_unused", view.bricksPrefetchedUnused);
        s.add("bricks_culled_by_sub_blocks", view.bricksCulledBySubBlocks);
        s.add("polygons_hidden", view.polygonsHidden);
    }
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
    bool helpShown = false;
    const ExtractOptions o = parseExtractOptions(argc, argv, helpShown);
    if (helpShown) return 0;
    // Existing outputs are refused before the work starts, not after minutes of extraction.
    refuseExistingOutputs({&o.meshPath, &o.pngPath, &o.statsPath, &o.pointsPath}, o.overwrite);

    const BrickStoreReader store(o.input, o.cold ? ReadMode::Cold : ReadMode::Buffered);
    BrickCache cache(store, o.cacheMb << 20);
    if (o.level >= store.header().levelCount)
        throw UsageError("--level " + std::to_string(o.level) + ": " + o.input + " holds " +
                         std::to_string(store.header().levelCount) + " level" +
                         (store.header().levelCount == 1 ? "" : "s") + " of detail (0 to " +
                         std::to_string(store.header().levelCount - 1) + ")");
    const VolumeInfo& volume = store.volume();
    const glm::dvec3 boundsMin = volume.origin;
    const glm::dvec3 boundsMax = volume.worldMax();
    // Presets face the patient's front on a store with orientation (or the side asked for).
    ViewFacing facing = defaultFacing();
    try {
        facing = viewFacing(o.view.side, volume);
    } catch (const std::invalid_argument& e) {
        throw UsageError("--view " + viewChoiceName(o.view) + ": " + o.input + ": " + e.what());
    }
    ViewChoice view = o.view;
    if (!view.side && volume.hasOrientation) view.side = PatientSide::Anterior;
    // The cameras: one (or none for a full extraction without a picture), or a path.
    std::vector<Camera> cameras;
    if (o.orbitFrames > 0)
        cameras = orbitCameras(view.distance, facing, boundsMin, boundsMax, o.width, o.height, o.orbitFrames);
    else if (!o.pathFile.empty())
        cameras = readCameraPath(o.pathFile, o.width, o.height);
    else if (!o.cameraPath.empty())
        cameras.push_back(readCameraJson(o.cameraPath, o.width, o.height));
    else if (!o.pngPath.empty() || isViewDependent(o.method))
        cameras.push_back(presetCamera(view.distance, facing, boundsMin, boundsMax, o.width, o.height));
    for (Camera& c : cameras)
        if (!c.hasClipPlanes()) fitClipPlanes(c, boundsMin, boundsMax);
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
