#include "cli/extract_options.h"

#include <cctype>
#include <stdexcept>

#include "app/view_camera.h"
#include "cli/args.h"
#include "core/view_presets.h"
#include "io/camera_json.h"
#include "io/mesh/mesh_writer.h"

namespace vdiso::cli {

const char* const kExtractHelp =
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
    "                            (default), closeup, or a multiple of the normal distance (2.5:\n"
    "                            that much farther; distant is about 10). SIDE, for a store\n"
    "                            with orientation: the side of the patient the camera looks\n"
    "                            at, anterior (default: a head's face, upright), posterior,\n"
    "                            left, right (superior up), superior or inferior (anterior\n"
    "                            up); e.g. --view left,\n"
    "                            --view closeup,anterior. A store without orientation is seen\n"
    "                            from the front (+y), a little from the side and above, +z up.\n"
    "                            (A mirrored grid, e.g. stored radiologically, is drawn in\n"
    "                            volume space: left and right swap; up stays up.)\n"
    "  --camera CAM.json         camera from a file: {\"eye\":[..],\"target\":[..],\"up\":[..],\n"
    "                            \"fov\":30,\"width\":800,\"height\":600}\n"
    "  --size WxH                image size (default 800x800)\n"
    "  --stats STATS.json        write one JSON object of statistics ('-' for stdout)\n"
    "  --metacell M              meta-cell size in cells, 1 to 32 (default 8)\n"
    "  --threads N               extraction threads (default: the machine's cores); sage and\n"
    "                            wise split the image into N vertical strips, one traversal each\n"
    "  --prefetch N              bricks a reader thread loads ahead of the extraction\n"
    "                            (default 32; 0: none): for sage/wise those a look-ahead finds\n"
    "                            visible; for octree/noise the active bricks, with --threads 1\n"
    "                            (with more threads no reader thread runs: stats say prefetch 0)\n"
    "  --readers N               threads reading those bricks, so N reads wait on the disk at\n"
    "                            once (default 2, at most the cores beside the extraction);\n"
    "                            a store at a URL reads ahead 128 with at most 2 a strip,\n"
    "                            which keep as many requests in flight as the link holds\n"
    "                            (at most --connections; 32 for an indexed array's chunks)\n"
    "  --cache-mb N              brick cache budget in MB (default 1024)\n"
    "  --cold                    drop the store's pages from the page cache first and read\n"
    "                            every brick from disk (O_DIRECT), so io_s is disk time\n"
    "  --force                   replace existing output files\n"
    "  --quiet                   no progress bar or summary\n";

namespace {


void parseSize(const std::string& text, int& width, int& height) {
    const size_t x = text.find('x');
    if (x == std::string::npos) throw UsageError("--size expects WxH, not '" + text + "'");
    width = int(parseInt("--size", text.substr(0, x), kMinImageSide, kMaxImageSide));
    height = int(parseInt("--size", text.substr(x + 1), kMinImageSide, kMaxImageSide));
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

}  // namespace

ExtractOptions parseExtractOptions(int argc, char** argv) {
    Args args(argc, argv, 1);
    ExtractOptions o;
    while (!args.done()) {
        const std::string a = args.take();
        if (a == "--help" || a == "-h") {
            o.help = true;
            return o;
        } else if (a == "--iso") {
            o.iso = parseDouble(a, args.value(a));
        } else if (a == "--method") {
            o.method = args.value(a);
        } else if (a == "--lod-error") {
            o.lodError = parseDouble(a, args.value(a));
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
            o.post.decimateRatio = parseDouble(a, args.value(a));
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
            o.prefetchGiven = true;
        } else if (a == "--readers") {
            o.readers = int(parseInt(a, args.value(a), 1, 64));
            o.readersGiven = true;
        } else if (takeRemoteOption(a, args, o.remote)) {
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
    if (o.viewGiven && !o.cameraPath.empty()) throw UsageError("give --view or --camera, not both");
    const bool viewDependent = isViewDependent(o.method);
    if (o.pngPath.empty() && !viewDependent && o.orbitFrames == 0 && o.pathFile.empty() &&
        (o.viewGiven || !o.cameraPath.empty()))
        throw UsageError("--view and --camera frame the picture: they need --png (or a "
                         "view-dependent --method)");
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

std::vector<Camera> extractCameras(const ExtractOptions& o, const VolumeInfo& volume, ViewChoice& view) {
    view = o.view;
    const ViewFacing facing = chooseFacing(view, volume);
    // The cameras: one (or none for a full extraction without a picture), or a path.
    std::vector<Camera> cameras;
    if (o.orbitFrames > 0)
        cameras = orbitCameras(view.distance, facing, volume.origin, volume.worldMax(), o.width, o.height,
                               o.orbitFrames, view.times);
    else if (!o.pathFile.empty())
        cameras = readCameraPath(o.pathFile, o.width, o.height);
    else if (!o.cameraPath.empty())
        cameras.push_back(readCameraJson(o.cameraPath, o.width, o.height));
    else if (!o.pngPath.empty() || isViewDependent(o.method))
        cameras.push_back(presetCamera(view.distance, facing, volume.origin, volume.worldMax(), o.width, o.height,
                                       view.times));
    for (Camera& c : cameras) fitClipPlanes(c, volume);  // once, for every kind
    return cameras;
}

}  // namespace vdiso::cli
