// vdiso.marching_cubes: scikit-image's signature and conventions over the octree method, on the
// array in place (app/array_brick_source.h).
#include <pybind11/stl.h>

#include <algorithm>
#include <cfloat>
#include <cmath>
#include <optional>
#include <span>
#include <vector>
#include <stdexcept>
#include <thread>

#include "app/array_brick_source.h"
#include "app/slab_extraction.h"
#include "array_slices.h"
#include "app/extract_settings.h"
#include "arrays.h"
#include "bindings.h"
#include "core/extract/extract_full.h"
#include "released.h"

namespace vdiso::py {

namespace pyb = pybind11;

namespace {

// The bricks marching_cubes meshes an array in (cells a side): in memory, a layer at a time and
// on a cluster alike, so the mesh is the same (Python cuts masks and runs by it).
constexpr int kBrick = 32;

// scikit-image's value of a cell (its "measure of the data near each vertex", for colour maps):
// the spread max(0, largest corner - level) - min(0, smallest corner - level), the corners read as
// float32.
double cellSpread(double top, double bottom, double level) {
    return std::max(0.0, double(float(top)) - level) - std::min(0.0, double(float(bottom)) - level);
}

// scikit-image's `values` (its "measure of the data near each vertex", for colour maps): the
// largest spread, max(0, largest corner - level) - min(0, smallest corner - level), of the cells
// whose triangles use the vertex, which are the cells around the edge it lies on (up to four,
// those in the volume), its samples read as float32 as scikit-image reads them. The edge is
// found from the position: the vertex lies inside it along one axis, at whole sample
// coordinates along the others. `s` holds the volume's rows (z) from `firstRow` (a layer's, its
// ghost rows included), those of the cells around `positions`.
template <class S>
void cellSpreads(const StridedSamples& s, int64_t firstRow, int64_t depth, double level,
                 std::span<const glm::vec3> positions, const glm::dvec3& spacing, float* values) {
    const auto* base = static_cast<const unsigned char*>(s.data);
    const int64_t dims[3] = {s.dims[0], s.dims[1], depth};
    const int64_t rowEnd = firstRow + s.dims[2];
    // A vertex's edge: its first sample and axis; interior when every column around it is held.
    struct Edge {
        int64_t at[3];
        int axis;
        bool interior;
        const unsigned char* first;  // interior: the column at (-1, -1) across the edge
        bool inCell;  // a vertex inside cell `at` (method="lewiner"'s, core/kernel/trilinear_cell.h)
    };
    auto edgeOf = [&](size_t v, Edge& e) {
        // Floors by truncation and one comparison (no libm call: a third of the pass's time).
        int64_t whole[3];
        double frac[3];
        double farthest = -1, next = -1;
        for (int a = 0; a < 3; ++a) {
            const double g = positions[v][a] / spacing[a];
            whole[a] = int64_t(g);
            whole[a] -= double(whole[a]) > g;
            frac[a] = g - double(whole[a]);
            const double off = std::min(frac[a], 1.0 - frac[a]);
            if (off > farthest) {
                next = farthest;
                farthest = off;
                e.axis = a;
            } else {
                next = std::max(next, off);
            }
        }
        // Off the grid's lines on two axes: inside a cell; its value is that cell's spread.
        e.inCell = next > 1e-3;
        if (e.inCell) {
            for (int a = 0; a < 3; ++a) e.at[a] = std::clamp<int64_t>(whole[a], 0, dims[a] - 2);
            e.interior = false;
            e.first = nullptr;
            return;
        }
        for (int a = 0; a < 3; ++a)
            e.at[a] = a == e.axis ? std::clamp<int64_t>(whole[a], 0, dims[a] - 2) : whole[a] + (frac[a] >= 0.5);
        const int b = (e.axis + 1) % 3, c = (e.axis + 2) % 3;
        e.interior = e.at[b] >= 1 && e.at[b] <= dims[b] - 2 && e.at[c] >= 1 && e.at[c] <= dims[c] - 2 &&
                     e.at[2] - 1 >= firstRow && e.at[2] + 1 < rowEnd;
        e.first = !e.interior ? nullptr
                              : base + e.at[0] * s.strides[0] + e.at[1] * s.strides[1] +
                                    (e.at[2] - firstRow) * s.strides[2] - s.strides[b] - s.strides[c];
    };
    // The volume is cold by the time its vertices are known (a whole mesh, a layer's): the
    // columns of the vertices kAhead ahead are fetched while this one is worked out (without,
    // the misses cost more than the rest of the pass).
    constexpr size_t kAhead = 16;
    Edge ring[kAhead];
    auto fetchAhead = [&](size_t v) {
        Edge& e = ring[v % kAhead];
        edgeOf(v, e);
        if (!e.interior) return;
        const int64_t sa = s.strides[e.axis], sb = s.strides[(e.axis + 1) % 3], sc = s.strides[(e.axis + 2) % 3];
        for (int j = 0; j < 3; ++j)
            for (int i = 0; i < 3; ++i) {
                __builtin_prefetch(e.first + j * sc + i * sb);
                if (e.axis != 0) __builtin_prefetch(e.first + j * sc + i * sb + sa);
            }
    };
    const size_t n = positions.size();
    for (size_t v = 0; v < std::min(n, kAhead); ++v) fetchAhead(v);
    for (size_t v = 0; v < n; ++v) {
        const Edge e = ring[v % kAhead];
        if (v + kAhead < n) fetchAhead(v + kAhead);
        if (e.inCell) {
            values[v] = 0;
            if (e.at[2] < firstRow || e.at[2] + 1 >= rowEnd) continue;  // (its layer holds its rows)
            S top = 0, bottom = 0;
            for (int k = 0; k < 8; ++k) {
                const unsigned char* q = base + (e.at[0] + (k & 1)) * s.strides[0] + (e.at[1] + (k >> 1 & 1)) * s.strides[1] +
                                         (e.at[2] + (k >> 2) - firstRow) * s.strides[2];
                S sample;
                std::memcpy(&sample, q, sizeof sample);
                top = k == 0 || sample > top ? sample : top;
                bottom = k == 0 || sample < bottom ? sample : bottom;
            }
            values[v] = float(cellSpread(double(top), double(bottom), level));
            continue;
        }
        const int b = (e.axis + 1) % 3, c = (e.axis + 2) % 3;
        const int64_t sa = s.strides[e.axis], sb = s.strides[b], sc = s.strides[c];
        // The 3 x 3 columns of two samples along the edge around it, as their largest and
        // smallest (compared as S: float32 rounding keeps the order); each cell around the edge is
        // 2 x 2 of them. A column outside the volume or the rows held has none; an interior
        // edge's (most) are all held, at fixed steps from its first.
        S hi[9], lo[9];
        bool held[9];
        for (int j = 0; j < 3; ++j)
            for (int i = 0; i < 3; ++i) {
                const int k = 3 * j + i;
                const unsigned char* q = nullptr;
                if (e.interior) {
                    q = e.first + j * sc + i * sb;
                } else {
                    int64_t p[3] = {e.at[0], e.at[1], e.at[2]};
                    p[b] += i - 1;
                    p[c] += j - 1;
                    held[k] = p[b] >= 0 && p[b] < dims[b] && p[c] >= 0 && p[c] < dims[c] && p[2] >= firstRow &&
                              p[2] + (e.axis == 2) < rowEnd;
                    if (!held[k]) continue;
                    q = base + p[0] * s.strides[0] + p[1] * s.strides[1] + (p[2] - firstRow) * s.strides[2];
                }
                held[k] = true;
                S s0, s1;
                std::memcpy(&s0, q, sizeof s0);
                std::memcpy(&s1, q + sa, sizeof s1);
                hi[k] = s0 > s1 ? s0 : s1;
                lo[k] = s0 < s1 ? s0 : s1;
            }
        double best = 0;
        for (int k = 0; k < 4; ++k) {
            const int o = 3 * (k >> 1) + (k & 1);
            if (!(held[o] && held[o + 1] && held[o + 3] && held[o + 4])) continue;
            const S top = std::max(std::max(hi[o], hi[o + 1]), std::max(hi[o + 3], hi[o + 4]));
            const S bottom = std::min(std::min(lo[o], lo[o + 1]), std::min(lo[o + 3], lo[o + 4]));
            best = std::max(best, cellSpread(double(top), double(bottom), level));
        }
        values[v] = float(best);
    }
}

// The level asked for, or the middle of the values `range` (NaN left out) for none, checked as
// scikit-image checks it.
double levelIn(std::optional<double> given, const BrickRange& range) {
    const float lo = range.minValue, hi = range.maxValue;
    // No level: the middle of the values (NaN left out), as scikit-image takes it.
    if (!given && !(std::isfinite(lo) && std::isfinite(hi)))
        throw std::invalid_argument("volume: has no finite sample, so no level lies in its values");
    const double level = given ? *given : 0.5 * (double(lo) + double(hi));
    // As scikit-image: a level outside the values is a mistake, not an empty surface.
    if (!(level >= lo && level <= hi))
        throw std::invalid_argument("level: " + std::to_string(level) + " is outside the volume's values (" +
                                    std::to_string(lo) + " to " + std::to_string(hi) + ")");
    return level;
}

// What a layer of an array read a layer at a time adds to marching_cubes' `values`: those of the
// vertices it made, from its slices while they are held (SlabExtractOptions::layerDone).
auto appendValues(const VolumeInfo& info, double level, std::vector<float>& values) {
    return [&info, level, &values](const StridedSamples& rows, int64_t firstRow, std::span<const glm::vec3> added) {
        const size_t first = values.size();
        values.resize(first + added.size());
        visitFileScalar(rows.type, [&](auto zero) {
            cellSpreads<decltype(zero)>(rows, firstRow, info.dims[2], level, added, info.spacing, values.data() + first);
        });
    };
}

// An array's shape as (z, y, x); zeros when it is not 3-D (arrayVolumeInfo refuses it, by name).
std::array<int64_t, 3> zyxOf(const std::vector<int64_t>& shape) {
    return shape.size() == 3 ? std::array<int64_t, 3>{shape[0], shape[1], shape[2]} : std::array<int64_t, 3>{};
}

// `shape`: the array's (z, y, x), as `spacing`. The vertices are float32 before they are scaled:
// a spacing that carries the array's extent beyond float32's range is refused.
void checkLevelAndSpacing(std::optional<double> level, const std::array<double, 3>& spacing,
                          const std::array<int64_t, 3>& shape) {
    if (level && !std::isfinite(*level))
        throw std::invalid_argument("level: expects a finite isovalue, not " + std::to_string(*level));
    for (double s : spacing)
        if (!(s > 0 && std::isfinite(s)))
            throw std::invalid_argument("spacing: expects three positive finite numbers, not " + std::to_string(s));
    for (int a = 0; a < 3; ++a)
        if (spacing[size_t(a)] * double(std::max<int64_t>(shape[size_t(a)] - 1, 1)) > double(FLT_MAX) / 2)
            throw std::invalid_argument("spacing: " + pyb::str(pyb::float_(spacing[size_t(a)])).cast<std::string>() + " along axis " +
                                        std::to_string(a) + " over its " + std::to_string(shape[size_t(a)]) +
                                        " samples puts vertices beyond float32's range");
}

// marching_cubes' four arrays over `mesh` (x, y, z in index units times spacing) and `values`:
// the mesh's own buffers become the arrays (owned by a capsule), so peak memory is the output
// once, not twice. NumPy's axis order is z, y, x: each row is reversed in place.
pyb::tuple meshArrays(TriangleMesh&& mesh, pyb::array_t<float> values, const std::array<double, 3>& spacing) {
    auto* owned = new TriangleMesh(std::move(mesh));
    const pyb::capsule owner(owned, [](void* p) { delete static_cast<TriangleMesh*>(p); });
    const size_t n = owned->positions.size(), m = owned->triangleCount();
    if (n > size_t(INT32_MAX))
        throw std::runtime_error("the surface has " + std::to_string(n) + " vertices, more than scikit-image's int32 "
                                 "faces can number: use vdiso.convert and Store.extract (uint32 faces)");
    for (size_t v = 0; v < n; ++v) {
        std::swap(owned->positions[v].x, owned->positions[v].z);
        std::swap(owned->normals[v].x, owned->normals[v].z);
    }
    // scikit-image's vertices: float32, or float64 once scaled by a spacing other than 1.
    const bool unit = spacing[0] == 1 && spacing[1] == 1 && spacing[2] == 1;
    pyb::array verts;
    if (unit) {
        verts = arrayOver(rowsOrEmpty(&owned->positions.data()->x), n, 3, owner);
    } else {
        pyb::array_t<double> wide({n, size_t(3)});
        std::copy_n(&owned->positions.data()->x, 3 * n, wide.mutable_data());
        MeshArray<glm::vec3>().swap(owned->positions);
        verts = wide;
    }
    // Vertex numbers fit 31 bits (the library numbers them in 32): the same bytes as int32.
    static_assert(sizeof(int32_t) == sizeof(uint32_t));
    const pyb::array faces = arrayOver(rowsOrEmpty(reinterpret_cast<const int32_t*>(owned->indices.data())), m, 3, owner);
    const pyb::array normals = arrayOver(rowsOrEmpty(&owned->normals.data()->x), n, 3, owner);
    return pyb::make_tuple(verts, faces, normals, values);
}

// `bricks`: when given, only these bricks (kBrick cells a side, numbered x fastest) are meshed,
// as a part of the array (FullExtractOptions::bricks): the triangles of their cells, vertices
// numbered as the whole array's would be.
pyb::tuple marchingCubes(const pyb::array& volume, std::optional<double> givenLevel, std::array<double, 3> spacing,
                         std::optional<int64_t> threads, pyb::object progress, std::optional<std::vector<int64_t>> bricks,
                         bool trilinear) {
    // Every check on the arguments and the array's size comes before any pass over its samples.
    const StridedSamples samples = stridedSamplesOf(volume, "volume");
    checkLevelAndSpacing(givenLevel, spacing, {samples.dims[2], samples.dims[1], samples.dims[0]});
    const int threadCount = threads ? int(checkedInt("threads", *threads, 1, 256)) : machineThreads();
    // The kernel's x, y, z are NumPy's axes 2, 1, 0.
    const glm::dvec3 xyzSpacing(spacing[2], spacing[1], spacing[0]);
    TriangleMesh mesh;
    double level = 0;
    std::vector<float> spreads;  // the values
    runReleased([&](const ProgressFn& fraction) {
        ArrayBrickSource source(samples, kBrick, xyzSpacing, threadCount);
        BrickRange range = kNoRange;
        for (const BrickRange& r : source.brickRanges()) range = unite(range, r);
        level = levelIn(givenLevel, range);
        FullExtractOptions options{level, kDefaultMetaCellSize, threadCount};
        options.trilinear = trilinear;
        if (bricks) {
            std::sort(bricks->begin(), bricks->end());
            bricks->erase(std::unique(bricks->begin(), bricks->end()), bricks->end());
            if (bricks->empty()) return;  // nothing to mesh
            options.bricks = *bricks;
        }
        extractOctree(source, options, mesh, fraction);
        // The values on the extraction's threads, a run of vertices each.
        spreads.resize(mesh.positions.size());
        const size_t n = spreads.size(), runs = size_t(std::max(threadCount, 1));
        std::vector<std::thread> workers;
        for (size_t r = 0; r < runs; ++r) {
            const size_t first = n * r / runs, end = n * (r + 1) / runs;
            auto work = [&, first, end] {
                visitFileScalar(samples.type, [&](auto zero) {
                    cellSpreads<decltype(zero)>(samples, 0, samples.dims[2], level,
                                                std::span(mesh.positions).subspan(first, end - first), xyzSpacing,
                                                spreads.data() + first);
                });
            };
            if (r + 1 == runs) work();
            else workers.emplace_back(work);
        }
        for (std::thread& w : workers) w.join();
    }, progress, double(samples.dims[0]) * double(samples.dims[1]) * double(samples.dims[2]));
    pyb::array_t<float> values(spreads.size());
    std::copy(spreads.begin(), spreads.end(), values.mutable_data());
    return meshArrays(std::move(mesh), values, spacing);
}

// cellSpread of each row of `corners` (K, 8): the cells' samples, gathered by the caller
// (marching_cubes' values with a mask, python/vdiso/_marching_cubes.py).
pyb::array_t<float> cellSpreadsOf(pyb::array_t<double, pyb::array::c_style | pyb::array::forcecast> corners, double level) {
    if (corners.ndim() != 2 || corners.shape(1) != 8) throw std::invalid_argument("corners: expects (K, 8) samples");
    const auto c = corners.unchecked<2>();
    pyb::array_t<float> out(corners.shape(0));
    float* o = out.mutable_data();
    for (pyb::ssize_t k = 0; k < corners.shape(0); ++k) {
        double top = c(k, 0), bottom = c(k, 0);
        for (int i = 1; i < 8; ++i) {
            top = std::max(top, c(k, i));
            bottom = std::min(bottom, c(k, i));
        }
        o[k] = float(cellSpread(top, bottom, level));
    }
    return out;
}

// marching_cubes of an array-like too large to load (Dask, Zarr, anything sliced along axis 0):
// read once in order a layer of bricks at a time (app/slab_extraction.h), each chunk of
// `bounds` computed or decoded once; with no level, read once more before, for its range.
// `bricks`: when given, only these are meshed (SlabExtractOptions::onlyBricks).
pyb::tuple marchingCubesInSlabs(pyb::object source, const std::string& name, const std::vector<int64_t>& shape,
                                const pyb::dtype& dtype, std::optional<double> givenLevel,
                                std::array<double, 3> spacing, std::optional<int64_t> threads,
                                const std::vector<int64_t>& bounds, pyb::object progress,
                                std::optional<std::vector<int64_t>> bricks, bool trilinear) {
    checkLevelAndSpacing(givenLevel, spacing, zyxOf(shape));
    if (bricks) {
        std::sort(bricks->begin(), bricks->end());
        bricks->erase(std::unique(bricks->begin(), bricks->end()), bricks->end());
    }
    const FileScalar type = fileScalarOfDtype(dtype, name.c_str());
    const VolumeInfo info = arrayVolumeInfo(name, shape, type, spacing, {0.0, 0.0, 0.0});
    checkChunkBounds(name, shape, bounds);
    const int threadCount = threads ? int(checkedInt("threads", *threads, 1, 256)) : machineThreads();
    TriangleMesh mesh;
    std::vector<float> values;
    const double samplesTotal = double(info.sampleCount());
    runReleased([&](const ProgressFn& fraction) {
        std::optional<double> level = givenLevel;
        double start = 0;
        if (!level) {  // its range first: a pass of its own
            ArraySlices slices(source, info, type, name, bounds);
            level = levelIn(std::nullopt, sliceRange(slices, kBrick, threadCount, [&](double f) { fraction(0.5 * f); }));
            start = 0.5;
        }
        ArraySlices slices(source, info, type, name, bounds);
        SlabExtractOptions options;
        options.extract = FullExtractOptions{*level, kDefaultMetaCellSize, threadCount};
        options.extract.trilinear = trilinear;
        options.brickSize = kBrick;
        options.onlyBricks = bricks;
        options.layerDone = appendValues(info, *level, values);
        const SlabExtractResult result =
            extractSlabs(slices, options, mesh, [&](double f) { fraction(start + (1 - start) * f); });
        levelIn(level, result.range);  // a level given outside the values
    }, progress, samplesTotal);
    pyb::array_t<float> out(values.size());
    std::copy(values.begin(), values.end(), out.mutable_data());
    return meshArrays(std::move(mesh), out, spacing);
}

// One run of layers [firstLayer, endLayer) of an array of `shape` meshed alone, from `rows`, its
// slices from the run's first (its ghost below included) to its last layer's ghosts above: what
// a worker of a Dask cluster runs. Returns its arrays (positions and normals x, y, z; indices;
// values) and border (edge keys and their vertices) and its samples' range, for
// _join_slab_parts.
pyb::dict meshSlabPart(pyb::object rows, const std::vector<int64_t>& shape, const pyb::dtype& dtype,
                       int64_t firstLayer, int64_t endLayer, double level, std::array<double, 3> spacing,
                       int64_t threads, bool trilinear) {
    checkLevelAndSpacing(level, spacing, zyxOf(shape));
    const std::string name = "rows of the array";
    const FileScalar type = fileScalarOfDtype(dtype, name.c_str());
    const VolumeInfo info = arrayVolumeInfo(name, shape, type, spacing, {0.0, 0.0, 0.0});
    SlabPart part;
    std::vector<float> values;
    runReleased([&](const ProgressFn&) {
        ArraySlices slices(rows, info, type, name, {});
        SlabExtractOptions options;
        options.extract = FullExtractOptions{level, kDefaultMetaCellSize, int(checkedInt("threads", threads, 1, 256))};
        options.extract.trilinear = trilinear;
        options.layerDone = appendValues(info, level, values);
        part = extractSlabPart(slices, options, firstLayer, endLayer);
    });
    const size_t n = part.mesh.positions.size();
    pyb::array_t<uint64_t> keys(part.border.size());
    pyb::array_t<uint32_t> vertices(part.border.size());
    size_t k = 0;
    part.border.forEach([&](uint64_t key, uint32_t v) {
        keys.mutable_data()[k] = key;
        vertices.mutable_data()[k++] = v;
    });
    auto copy = [](const auto* data, size_t count) {
        pyb::array_t<std::remove_const_t<std::remove_pointer_t<decltype(data)>>> out(count);
        std::copy_n(data, count, out.mutable_data());
        return out;
    };
    return pyb::dict(pyb::arg("positions") = copy(&rowsOrEmpty(part.mesh.positions.data())->x, 3 * n),
                     pyb::arg("normals") = copy(&rowsOrEmpty(part.mesh.normals.data())->x, 3 * n),
                     pyb::arg("indices") = copy(rowsOrEmpty(part.mesh.indices.data()), part.mesh.indices.size()),
                     pyb::arg("values") = copy(rowsOrEmpty(values.data()), values.size()),
                     pyb::arg("border_keys") = keys, pyb::arg("border_vertices") = vertices,
                     pyb::arg("range") = pyb::make_tuple(part.range.minValue, part.range.maxValue));
}

// marching_cubes' arrays from the parts of meshSlabPart, in the order of their runs, which cover
// the array: welded into the mesh of the array meshed whole. `level` is checked against their
// samples' range.
pyb::tuple joinSlabPartArrays(const pyb::list& given, double level, std::array<double, 3> spacing) {
    std::vector<SlabPart> parts(given.size());
    std::vector<std::vector<float>> values(given.size());
    BrickRange range = kNoRange;
    for (size_t p = 0; p < parts.size(); ++p) {
        const pyb::dict d = given[p].cast<pyb::dict>();
        auto array = [&](const char* key, auto zero) {
            return d[key].cast<pyb::array_t<decltype(zero), pyb::array::c_style | pyb::array::forcecast>>();
        };
        const auto positions = array("positions", 0.0f), normals = array("normals", 0.0f), vals = array("values", 0.0f);
        const auto indices = array("indices", uint32_t(0));
        const auto keys = array("border_keys", uint64_t(0));
        const auto numbers = array("border_vertices", uint32_t(0));
        const size_t n = size_t(vals.size());
        if (size_t(positions.size()) != 3 * n || size_t(normals.size()) != 3 * n || keys.size() != numbers.size())
            throw std::invalid_argument("a mesh part: arrays of unequal lengths");
        if (indices.size() % 3 != 0)
            throw std::invalid_argument("a mesh part: " + std::to_string(indices.size()) +
                                        " face indices, not three a triangle");
        TriangleMesh& mesh = parts[p].mesh;
        mesh.positions.resize(n);
        mesh.normals.resize(n);
        std::copy_n(positions.data(), 3 * n, reinterpret_cast<float*>(mesh.positions.data()));
        std::copy_n(normals.data(), 3 * n, reinterpret_cast<float*>(mesh.normals.data()));
        mesh.indices.assign(indices.data(), indices.data() + indices.size());
        for (const uint32_t i : mesh.indices)
            if (i >= n) throw std::invalid_argument("a mesh part: a face names vertex " + std::to_string(i) + " of " + std::to_string(n));
        for (pyb::ssize_t k = 0; k < keys.size(); ++k) {
            if (numbers.data()[k] >= n) throw std::invalid_argument("a mesh part: a border vertex beyond its vertices");
            parts[p].border.insert(keys.data()[k], numbers.data()[k]);
        }
        values[p].assign(vals.data(), vals.data() + n);
        const auto [lo, hi] = d["range"].cast<std::pair<float, float>>();
        range = unite(range, {lo, hi});
    }
    levelIn(level, range);
    TriangleMesh mesh;
    std::vector<float> joined;
    {
        pyb::gil_scoped_release release;
        joinSlabParts(parts, values, mesh, &joined);
    }
    pyb::array_t<float> out(joined.size());
    std::copy(joined.begin(), joined.end(), out.mutable_data());
    return meshArrays(std::move(mesh), out, spacing);
}

}  // namespace

void bindMarchingCubes(pyb::module_& m) {
    m.def("marching_cubes", &marchingCubes, pyb::arg("volume"), pyb::arg("level") = pyb::none(),
          pyb::arg("spacing") = std::array<double, 3>{1.0, 1.0, 1.0}, pyb::kw_only(),
          pyb::arg("threads") = pyb::none(), pyb::arg("progress") = pyb::none(), pyb::arg("bricks") = pyb::none(),
          pyb::arg("trilinear") = false, "The isosurface of a 3-D array (see vdiso.marching_cubes).");
    m.attr("_marching_cubes_brick") = kBrick;
    m.def("_cell_spreads", &cellSpreadsOf, pyb::arg("corners"), pyb::arg("level"));
    m.def("_marching_cubes_in_slabs", &marchingCubesInSlabs, pyb::arg("source"), pyb::arg("name"), pyb::arg("shape"),
          pyb::arg("dtype"), pyb::arg("level"), pyb::arg("spacing"), pyb::arg("threads"), pyb::arg("bounds"),
          pyb::arg("progress"), pyb::arg("bricks") = pyb::none(), pyb::arg("trilinear") = false,
          "marching_cubes of an array-like read a layer of bricks at a time (only `bricks` meshed, when given).");
    m.def("_mesh_slab_part", &meshSlabPart, pyb::arg("rows"), pyb::arg("shape"), pyb::arg("dtype"),
          pyb::arg("first_layer"), pyb::arg("end_layer"), pyb::arg("level"), pyb::arg("spacing"), pyb::arg("threads"),
          pyb::arg("trilinear") = false, "One run of layers of an array meshed alone (a Dask worker's part of marching_cubes).");
    m.def("_join_slab_parts", &joinSlabPartArrays, pyb::arg("parts"), pyb::arg("level"), pyb::arg("spacing"),
          "marching_cubes' arrays from the parts of _mesh_slab_part, welded.");
    m.def("_level_in", [](std::optional<double> level, float lo, float hi) { return levelIn(level, {lo, hi}); },
          pyb::arg("level"), pyb::arg("lo"), pyb::arg("hi"), "The level marching_cubes takes for the values [lo, hi].");
}

}  // namespace vdiso::py
