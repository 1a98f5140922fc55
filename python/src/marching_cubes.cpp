// vdiso.marching_cubes: scikit-image's signature and conventions over the octree method, on the
// array in place (app/array_brick_source.h).
#include <pybind11/stl.h>

#include <cmath>
#include <optional>
#include <stdexcept>

#include "app/array_brick_source.h"
#include "app/extract_settings.h"
#include "arrays.h"
#include "bindings.h"
#include "core/extract/extract_full.h"
#include "released.h"

namespace vdiso::py {

namespace pyb = pybind11;

namespace {

// scikit-image's `values`: a measure of the data near each vertex, for colour maps. Here the
// largest sample at the corners of the cell the vertex lies in (its lower corner at the floor
// of its sample coordinates).
template <class S>
void cellMaxima(const StridedSamples& s, const TriangleMesh& mesh, const glm::dvec3& spacing, float* values) {
    const auto* base = static_cast<const unsigned char*>(s.data);
    for (size_t v = 0; v < mesh.positions.size(); ++v) {
        int64_t corner[3];
        for (int a = 0; a < 3; ++a)
            corner[a] = std::clamp<int64_t>(int64_t(std::floor(mesh.positions[v][a] / spacing[a])), 0, s.dims[size_t(a)] - 2);
        double best = -INFINITY;
        for (int c = 0; c < 8; ++c) {
            S sample;
            std::memcpy(&sample,
                        base + (corner[0] + (c & 1)) * s.strides[0] + (corner[1] + ((c >> 1) & 1)) * s.strides[1] +
                            (corner[2] + (c >> 2)) * s.strides[2],
                        sizeof sample);
            best = std::max(best, double(sample));
        }
        values[v] = float(best);
    }
}

pyb::tuple marchingCubes(const pyb::array& volume, std::optional<double> givenLevel, std::array<double, 3> spacing,
                         std::optional<int64_t> threads, pyb::object progress) {
    // Every check on the arguments and the array's size comes before any pass over its samples.
    const StridedSamples samples = stridedSamplesOf(volume, "volume");
    if (givenLevel && !std::isfinite(*givenLevel))
        throw std::invalid_argument("level: expects a finite isovalue, not " + std::to_string(*givenLevel));
    for (double s : spacing)
        if (!(s > 0 && std::isfinite(s)))
            throw std::invalid_argument("spacing: expects three positive finite numbers, not " + std::to_string(s));
    const int threadCount = threads ? int(checkedInt("threads", *threads, 1, 256)) : machineThreads();
    double level = givenLevel.value_or(0.0);
    // The kernel's x, y, z are NumPy's axes 2, 1, 0.
    const glm::dvec3 xyzSpacing(spacing[2], spacing[1], spacing[0]);
    TriangleMesh mesh;
    runReleased([&](const ProgressFn& fraction) {
        ArrayBrickSource source(samples, 32, xyzSpacing, threadCount);
        // As scikit-image: a level outside the values is a mistake, not an empty surface.
        float lo = INFINITY, hi = -INFINITY;
        for (const BrickRange& r : source.brickRanges()) {
            lo = std::min(lo, r.minValue);
            hi = std::max(hi, r.maxValue);
        }
        // No level: the middle of the values (NaN left out), as scikit-image takes it.
        if (!givenLevel) {
            if (!(std::isfinite(lo) && std::isfinite(hi)))
                throw std::invalid_argument("volume: has no finite sample, so no level lies in its values");
            level = 0.5 * (double(lo) + double(hi));
        }
        if (!(level >= lo && level <= hi))
            throw std::invalid_argument("level: " + std::to_string(level) + " is outside the volume's values (" +
                                        std::to_string(lo) + " to " + std::to_string(hi) + ")");
        FullExtractOptions options{level, kDefaultMetaCellSize, threadCount};
        extractOctree(source, options, mesh, fraction);
    }, progress, double(samples.dims[0]) * double(samples.dims[1]) * double(samples.dims[2]));
    // The mesh's own buffers become the arrays (owned by a capsule): peak memory is the output
    // once, not twice. NumPy's axis order is z, y, x: each row is reversed in place.
    auto* owned = new TriangleMesh(std::move(mesh));
    const pyb::capsule owner(owned, [](void* p) { delete static_cast<TriangleMesh*>(p); });
    const size_t n = owned->positions.size(), m = owned->triangleCount();
    if (n > size_t(INT32_MAX))
        throw std::runtime_error("the surface has " + std::to_string(n) + " vertices, more than scikit-image's int32 "
                                 "faces can number: use vdiso.convert and Store.extract (uint32 faces)");
    pyb::array_t<float> values(n);
    visitFileScalar(samples.type, [&](auto zero) {
        cellMaxima<decltype(zero)>(samples, *owned, xyzSpacing, values.mutable_data());
    });
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

}  // namespace

void bindMarchingCubes(pyb::module_& m) {
    m.def("marching_cubes", &marchingCubes, pyb::arg("volume"), pyb::arg("level") = pyb::none(),
          pyb::arg("spacing") = std::array<double, 3>{1.0, 1.0, 1.0}, pyb::kw_only(),
          pyb::arg("threads") = pyb::none(), pyb::arg("progress") = pyb::none(),
          "The isosurface of a 3-D array (see vdiso.marching_cubes).");
}

}  // namespace vdiso::py
