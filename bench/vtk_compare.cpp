// vdiso's full extraction against VTK's, on the same volume and isovalue.
//
//   vdiso_vtk_compare FILE.vdiso --iso V [--vtk-threads N] [--threads N] [--repeat R] [--json]
//                     [--no-marching-cubes] [--views distant,normal,closeup] [--size N]
//
// Measures, per method, the median wall time of R extractions, the throughput in volume
// samples per second, and what came out: triangles, vertices and surface area (the sum of the
// triangles' areas, in world units, in double). The methods:
//   vdiso octree incl. decode  extractOctree over a cold BrickCache: bricks read and decoded
//   vdiso octree               the same with every brick already decoded (extraction alone)
//   vtkFlyingEdges3D           on the whole volume in a vtkImageData, vtkSMPTools on N threads
//   vtkMarchingCubes           the same volume; serial
//   vdiso sage VIEW            with --views: SAGE (default options, --threads strips) from the
//                              view preset at N x N, every brick decoded already and its
//                              meta-cell ranges kept from the run before (in memory, as VTK's
//                              volume is, and as a viewer's frames are)
//   vdiso sage VIEW from store the same from an empty brick cache and no ranges each run:
//                              bricks read (page cache warm) and decoded, as a first frame of
//                              `vdiso extract` does
// vdiso's octree rows use --threads too (default 1).
// VTK gets the volume fully in memory with the store's scalar type, spacing and origin, and
// computes normals as vdiso does (no gradients, no scalars), so the work is comparable.
//
// Why: to place vdiso's numbers next to a widely used implementation, and to check that both
// put the surface in the same place. Both cut the same edges (s > iso here, s >= iso in VTK:
// the same for isovalues between sample values) at the same linearly interpolated points, and
// VTK 9.1's case table splits every case into the same surface pieces as vdiso's (ambiguous
// faces separate the above corners; 358 pieces, 820 triangles over the 256 cases in both), so
// vertex and triangle counts match. Only the diagonals chosen inside each polygon differ
// (vdiso fans each polygon, core/kernel/mc_tables.h), which changes the area of non-planar polygons:
// by about 0.01% on smooth data, more on a surface that is rough at the scale of a voxel.
//
// VTK types appear in this file only.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <functional>
#include <stdexcept>
#include <string>
#include <vector>

// VTK 9.1's vtkSMPTools.h does not compile as C++20 (it declares a constructor with a
// template-id); vtkSMPTools::Initialize and GetEstimatedNumberOfThreads forward to this API.
#include <SMP/Common/vtkSMPToolsAPI.h>
#include <vtkCellArray.h>
#include <vtkDataArray.h>
#include <vtkFlyingEdges3D.h>
#include <vtkIdList.h>
#include <vtkImageData.h>
#include <vtkMarchingCubes.h>
#include <vtkNew.h>
#include <vtkPointData.h>
#include <vtkPoints.h>
#include <vtkPolyData.h>
#include <vtkType.h>

#include "cache/brick_cache.h"
#include "core/camera.h"
#include "core/extract/extract_full.h"
#include "core/extract/extract_view.h"
#include "core/mesh.h"
#include "core/scalar_type.h"
#include "core/view_presets.h"
#include "io/store/brick_store.h"

namespace {

using namespace vdiso;
using Clock = std::chrono::steady_clock;

struct Options {
    std::string path;
    double iso = 0;
    bool haveIso = false;
    int vtkThreads = 1;
    int repeat = 3;
    bool json = false;
    bool marchingCubes = true;
    int threads = 1;  // vdiso's
    std::vector<std::string> views;
    int size = 1024;
};

// What one method produced and how long it took.
struct MethodResult {
    std::string method;
    int threads = 1;
    int runs = 1;
    double seconds = 0;  // median over runs
    int64_t triangles = 0;
    int64_t vertices = 0;
    double area = 0;
};

[[noreturn]] void usage(const std::string& problem) {
    std::fprintf(stderr,
                 "vdiso_vtk_compare: %s\n"
                 "usage: vdiso_vtk_compare FILE.vdiso --iso V [--vtk-threads N] [--threads N] [--repeat R]\n"
                 "                         [--json] [--no-marching-cubes] [--views LIST] [--size N]\n",
                 problem.c_str());
    std::exit(2);
}

Options parseOptions(int argc, char** argv) {
    Options o;
    for (int i = 1; i < argc; ++i) {
        const std::string arg = argv[i];
        auto value = [&]() -> std::string {
            if (i + 1 >= argc) usage("missing value after " + arg);
            return argv[++i];
        };
        try {
            if (arg == "--iso") {
                o.iso = std::stod(value());
                o.haveIso = true;
            } else if (arg == "--vtk-threads") {
                o.vtkThreads = std::stoi(value());
            } else if (arg == "--threads") {
                o.threads = std::stoi(value());
            } else if (arg == "--views") {
                const std::string list = value();
                for (size_t at = 0; at <= list.size();) {
                    const size_t comma = std::min(list.find(',', at), list.size());
                    o.views.push_back(list.substr(at, comma - at));
                    parseViewPreset(o.views.back());
                    at = comma + 1;
                }
            } else if (arg == "--size") {
                o.size = std::stoi(value());
            } else if (arg == "--repeat") {
                o.repeat = std::stoi(value());
            } else if (arg == "--json") {
                o.json = true;
            } else if (arg == "--no-marching-cubes") {
                o.marchingCubes = false;
            } else if (!arg.empty() && arg[0] == '-') {
                usage("unknown option " + arg);
            } else if (o.path.empty()) {
                o.path = arg;
            } else {
                usage("more than one input file");
            }
        } catch (const std::invalid_argument& e) {
            usage(arg == "--views" ? e.what() : "bad number after " + arg);
        } catch (const std::logic_error&) {
            usage("bad number after " + arg);
        }
    }
    if (o.path.empty()) usage("no input file");
    if (!o.haveIso) usage("--iso is required");
    if (o.vtkThreads < 1) usage("--vtk-threads must be at least 1");
    if (o.repeat < 1) usage("--repeat must be at least 1");
    if (o.threads < 1) usage("--threads must be at least 1");
    if (o.size < kMinImageSide || o.size > kMaxImageSide) usage("--size must be in " + std::to_string(kMinImageSide) + ".." + std::to_string(kMaxImageSide));
    return o;
}

double secondsOf(const std::function<void()>& work) {
    const auto start = Clock::now();
    work();
    return std::chrono::duration<double>(Clock::now() - start).count();
}

double median(std::vector<double> values) {
    std::sort(values.begin(), values.end());
    const size_t n = values.size();
    return n % 2 ? values[n / 2] : 0.5 * (values[n / 2 - 1] + values[n / 2]);
}

// Bytes of memory the kernel could give us without swapping, from /proc/meminfo (0 if unknown).
uint64_t availableMemoryBytes() {
    std::ifstream meminfo("/proc/meminfo");
    std::string key;
    uint64_t kib = 0;
    std::string unit;
    while (meminfo >> key >> kib >> unit)
        if (key == "MemAvailable:") return kib * 1024;
    return 0;
}

double triangleArea(const double a[3], const double b[3], const double c[3]) {
    const double u[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
    const double v[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
    const double n[3] = {u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]};
    return 0.5 * std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
}

// Sum of the areas of the polygons of `poly` (triangles from both VTK filters; a polygon with
// more corners would be fanned).
double surfaceArea(vtkPolyData* poly) {
    vtkPoints* points = poly->GetPoints();
    vtkCellArray* polys = poly->GetPolys();
    if (!points || !polys) return 0;
    double area = 0;
    vtkNew<vtkIdList> cell;
    for (vtkIdType c = 0; c < polys->GetNumberOfCells(); ++c) {
        polys->GetCellAtId(c, cell);
        double first[3], previous[3], current[3];
        points->GetPoint(cell->GetId(0), first);
        for (vtkIdType k = 1; k < cell->GetNumberOfIds(); ++k) {
            points->GetPoint(cell->GetId(k), current);
            if (k >= 2) area += triangleArea(first, previous, current);
            std::copy(current, current + 3, previous);
        }
    }
    return area;
}

// A ratio for JSON: null when vdiso found no surface (JSON has no nan).
std::string jsonNumber(double value) {
    if (!std::isfinite(value)) return "null";
    char text[32];
    std::snprintf(text, sizeof text, "%.6f", value);
    return text;
}

int vtkScalarTypeOf(ScalarType t) {
    switch (t) {
        case ScalarType::U8: return VTK_UNSIGNED_CHAR;
        case ScalarType::I16: return VTK_SHORT;
        case ScalarType::U16: return VTK_UNSIGNED_SHORT;
        case ScalarType::F32: return VTK_FLOAT;
    }
    return VTK_FLOAT;
}

// Copies every sample of the volume once into `image`: each brick contributes the samples it
// owns (core/brick_layout.h), which sit one ghost in from the brick's first stored sample.
void fillImage(BrickSource& source, vtkImageData* image) {
    const VolumeInfo& volume = source.volume();
    const BrickLayout& layout = source.layout();
    const size_t sampleBytes = scalarSize(volume.type);
    const size_t side = size_t(layout.side());
    auto* destination = static_cast<unsigned char*>(image->GetScalarPointer());
    int64_t samplesCopied = 0;
    for (int64_t id = 0; id < layout.brickCount(); ++id) {
        const Dims3 coord = layout.brickCoord(id);
        int owned[3];
        int64_t first[3];
        for (int a = 0; a < 3; ++a) {
            owned[a] = layout.ownedSamplesOnAxis(a, coord[a]);
            first[a] = coord[a] * layout.brickSize;
        }
        const BrickHandle brick = source.acquire(id);
        const auto* samples = static_cast<const unsigned char*>(brick.samples());
        for (int z = 0; z < owned[2]; ++z) {
            for (int y = 0; y < owned[1]; ++y) {
                const size_t from = ((size_t(z + kGhostBefore) * side + size_t(y + kGhostBefore)) * side +
                                     kGhostBefore) * sampleBytes;
                const size_t to = ((size_t(first[2] + z) * size_t(volume.dims[1]) + size_t(first[1] + y)) *
                                       size_t(volume.dims[0]) + size_t(first[0])) * sampleBytes;
                std::memcpy(destination + to, samples + from, size_t(owned[0]) * sampleBytes);
            }
        }
        samplesCopied += int64_t(owned[0]) * owned[1] * owned[2];
    }
    if (samplesCopied != volume.sampleCount())
        throw std::runtime_error("bricks own " + std::to_string(samplesCopied) + " samples, volume has " +
                                 std::to_string(volume.sampleCount()));
    image->GetPointData()->GetScalars()->Modified();
}

MethodResult runVdiso(BrickCache& cache, double iso, int threads, int repeat, bool cold) {
    MethodResult r;
    r.method = cold ? "vdiso octree incl. decode" : "vdiso octree";
    r.threads = threads;
    r.runs = cold ? 1 : repeat;
    std::vector<double> seconds;
    for (int run = 0; run < r.runs; ++run) {
        TriangleMesh mesh;  // fresh each run, as VTK allocates a fresh output
        seconds.push_back(
            secondsOf([&] { extractOctree(cache, {iso, kDefaultMetaCellSize, threads}, mesh); }));
        if (run + 1 == r.runs) {
            r.triangles = int64_t(mesh.triangleCount());
            r.vertices = int64_t(mesh.vertexCount());
            r.area = surfaceArea(mesh);
        }
    }
    r.seconds = median(seconds);
    return r;
}

// SAGE from a view preset: in memory (`cache` holds every brick decoded), or from the store
// (a fresh cache per run, as large as `cache`). Points count as triangles in the row.
MethodResult runSage(const BrickStoreReader& store, BrickCache& cache, const Options& o,
                     const std::string& view, bool fromStore) {
    const VolumeInfo& volume = store.volume();
    Camera camera = presetCamera(parseViewPreset(view), volume.origin, volume.worldMax(), o.size, o.size);
    fitClipPlanes(camera, volume.origin, volume.worldMax());
    ViewExtractOptions options = ViewExtractOptions::sage(o.iso);
    options.threads = o.threads;
    options.prefetchBricks = 32;  // vdiso extract's default: reads ahead on 2 reader threads
    MethodResult r;
    r.method = "vdiso sage " + view + (fromStore ? " from store" : "");
    r.threads = o.threads;
    r.runs = o.repeat;
    std::vector<double> seconds;
    MetaCellRangeCache kept(size_t(store.layout().brickCount()));
    if (!fromStore) options.rangeCache = &kept;
    for (int run = 0; run < r.runs; ++run) {
        TriangleMesh mesh;
        PointSet points;
        if (fromStore) {
            BrickCache fresh(store, cache.budgetBytes());
            seconds.push_back(secondsOf([&] { extractViewDependent(fresh, camera, options, mesh, points); }));
        } else {
            seconds.push_back(secondsOf([&] { extractViewDependent(cache, camera, options, mesh, points); }));
        }
        r.triangles = int64_t(mesh.triangleCount() + points.positions.size());
        r.vertices = int64_t(mesh.vertexCount() + points.positions.size());
    }
    r.seconds = median(seconds);
    return r;
}

// Runs `filter` (already connected to its input) until `repeat` runs are done, or once when a
// single run takes longer than `slowSeconds`.
template <class Filter>
MethodResult runVtk(const char* name, Filter* filter, int threads, int repeat, double slowSeconds) {
    MethodResult r;
    r.method = name;
    r.threads = threads;
    std::vector<double> seconds;
    for (int run = 0; run < repeat; ++run) {
        filter->Modified();
        seconds.push_back(secondsOf([&] { filter->Update(); }));
        if (seconds.back() > slowSeconds) break;
    }
    r.runs = int(seconds.size());
    r.seconds = median(seconds);
    vtkPolyData* output = filter->GetOutput();
    r.triangles = output->GetNumberOfPolys();
    r.vertices = output->GetNumberOfPoints();
    r.area = surfaceArea(output);
    return r;
}

template <class Filter>
void configureFilter(Filter* filter, vtkImageData* image, double iso) {
    filter->SetInputData(image);
    filter->SetValue(0, iso);
    filter->ComputeNormalsOn();
    filter->ComputeGradientsOff();
    filter->ComputeScalarsOff();
}

}  // namespace

int main(int argc, char** argv) {
    const Options options = parseOptions(argc, argv);
    try {
        const BrickStoreReader store(options.path);
        const VolumeInfo& volume = store.volume();
        const BrickLayout& layout = store.layout();
        for (int a = 0; a < 3; ++a)
            if (volume.dims[a] > (int64_t(1) << 30)) throw std::runtime_error("volume too large for vtkImageData");

        // Every brick decoded at once, plus the volume for VTK, must fit in memory.
        const uint64_t cacheBytes = uint64_t(layout.brickCount()) * store.brickBytes();
        const uint64_t neededBytes = cacheBytes + volume.byteSize();
        const uint64_t availableBytes = availableMemoryBytes();
        if (availableBytes && neededBytes + neededBytes / 4 > availableBytes) {
            std::fprintf(stderr,
                         "vdiso_vtk_compare: %s needs %.0f MB (decoded bricks %.0f MB + volume %.0f MB) "
                         "and outputs; %.0f MB available\n",
                         options.path.c_str(), neededBytes / 1e6, cacheBytes / 1e6, volume.byteSize() / 1e6,
                         availableBytes / 1e6);
            return 1;
        }

        BrickCache cache(store, cacheBytes);
        std::vector<MethodResult> results;
        results.push_back(runVdiso(cache, options.iso, options.threads, options.repeat, /*cold=*/true));

        // Loading the image acquires every brick, so the warm runs below decode nothing.
        vtkNew<vtkImageData> image;
        image->SetDimensions(int(volume.dims[0]), int(volume.dims[1]), int(volume.dims[2]));
        image->SetSpacing(volume.spacing.x, volume.spacing.y, volume.spacing.z);
        image->SetOrigin(volume.origin.x, volume.origin.y, volume.origin.z);
        image->AllocateScalars(vtkScalarTypeOf(volume.type), 1);
        const double loadSeconds = secondsOf([&] { fillImage(cache, image); });
        results.push_back(runVdiso(cache, options.iso, options.threads, options.repeat, /*cold=*/false));
        for (const std::string& view : options.views) {
            results.push_back(runSage(store, cache, options, view, /*fromStore=*/false));
            results.push_back(runSage(store, cache, options, view, /*fromStore=*/true));
        }

        auto& vtkSmp = vtk::detail::smp::vtkSMPToolsAPI::GetInstance();
        vtkSmp.Initialize(options.vtkThreads);  // what vtkSMPTools::Initialize(N) does
        vtkNew<vtkFlyingEdges3D> flyingEdges;
        configureFilter(flyingEdges.Get(), image, options.iso);
        results.push_back(runVtk("vtkFlyingEdges3D", flyingEdges.Get(), vtkSmp.GetEstimatedNumberOfThreads(),
                                 options.repeat, /*slowSeconds=*/1e30));
        flyingEdges->GetOutput()->Initialize();  // free its output before the next filter runs

        if (options.marchingCubes) {
            vtkNew<vtkMarchingCubes> marchingCubes;
            configureFilter(marchingCubes.Get(), image, options.iso);
            results.push_back(runVtk("vtkMarchingCubes", marchingCubes.Get(), /*threads=*/1, options.repeat,
                                     /*slowSeconds=*/5.0));
        }

        const double voxels = double(volume.sampleCount());
        const MethodResult& reference = results[1];
        std::printf("%s: %lld x %lld x %lld %s, spacing %g %g %g, iso %g; image filled from bricks in %.3f s; "
                    "VTK SMP backend %s\n",
                    options.path.c_str(), (long long)volume.dims[0], (long long)volume.dims[1],
                    (long long)volume.dims[2], scalarTypeName(volume.type), volume.spacing.x, volume.spacing.y,
                    volume.spacing.z, options.iso, loadSeconds, vtkSmp.GetBackend());
        std::printf("%-26s %7s %4s %9s %10s %11s %11s %14s %10s %10s\n", "method", "threads", "runs", "seconds",
                    "Mvoxels/s", "triangles", "vertices", "area", "area ratio", "tri ratio");
        for (const MethodResult& r : results) {
            std::printf("%-26s %7d %4d %9.4f %10.1f %11lld %11lld %14.2f %10.5f %10.4f\n", r.method.c_str(),
                        r.threads, r.runs, r.seconds, voxels / r.seconds / 1e6, (long long)r.triangles,
                        (long long)r.vertices, r.area, r.area / reference.area,
                        double(r.triangles) / double(reference.triangles));
        }
        for (const MethodResult& r : results) {
            if (r.method.starts_with("vdiso sage")) continue;  // a view's surface, not the whole
            const double areaRatio = r.area / reference.area;
            if (std::abs(areaRatio - 1) > 0.005)
                std::printf("warning: %s area differs from vdiso's by %.2f%%\n", r.method.c_str(),
                            100 * (areaRatio - 1));
        }
        if (options.json) {
            for (const MethodResult& r : results) {
                std::printf("{\"method\":\"%s\",\"volume\":\"%s\",\"iso\":%.17g,\"threads\":%d,\"runs\":%d,"
                            "\"seconds\":%.6f,\"voxels_per_s\":%.6g,\"triangles\":%lld,\"vertices\":%lld,"
                            "\"area\":%.6f,\"area_ratio_to_vdiso\":%s,\"triangle_ratio_to_vdiso\":%s}\n",
                            r.method.c_str(), options.path.c_str(), options.iso, r.threads, r.runs, r.seconds,
                            voxels / r.seconds, (long long)r.triangles, (long long)r.vertices, r.area,
                            jsonNumber(r.area / reference.area).c_str(),
                            jsonNumber(double(r.triangles) / double(reference.triangles)).c_str());
            }
        }
    } catch (const std::exception& e) {
        std::fprintf(stderr, "vdiso_vtk_compare: %s\n", e.what());
        return 1;
    }
    return 0;
}
