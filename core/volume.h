// What a volume is, independent of where its samples live.
//
// A volume is a grid of dims[0] x dims[1] x dims[2] samples (x fastest). Sample (i,j,k) sits at
// origin + (i,j,k) * spacing in world units ("volume space": axis-aligned, where extraction,
// culling, cameras and rendering work). Cells are the (dims-1) cubes between samples.
//
// Physical space is where the scanner put the volume, in patient coordinates LPS (x towards the
// patient's Left, y Posterior, z Superior: DICOM's and ITK's convention): sample (i,j,k) sits at
// origin + direction * ((i,j,k) * spacing). The two spaces share the origin (sample 0,0,0) and
// differ by the direction's rotation (or flip, or shear) about it; core/orientation.h maps one to
// the other. Meshes are written in physical space; everything else stays in volume space.
#pragma once

#include <array>
#include <cstdint>
#include <string>

#include <glm/mat3x3.hpp>
#include <glm/mat4x4.hpp>
#include <glm/vec3.hpp>

#include "core/checked_math.h"
#include "core/scalar_type.h"

namespace vdiso {

using Dims3 = std::array<int64_t, 3>;

// What vdiso accepts (docs/store-format.md, "Limits"): at most 2^31 samples on an axis and 2^48
// in all, so every size derived from them (bytes, bricks, index bytes) fits 64 bits with room.
constexpr int64_t kMaxAxisSamples = int64_t(1) << 31;
constexpr int64_t kMaxVolumeSamples = int64_t(1) << 48;

// "" when `dims` is within the limits above (and every axis has the 2 samples cells need), else
// what is wrong, in words, for a reader to prefix with its file's name.
inline std::string volumeDimsProblem(const Dims3& dims) {
    const std::string text = std::to_string(dims[0]) + " x " + std::to_string(dims[1]) + " x " +
                             std::to_string(dims[2]) + " samples";
    for (int64_t d : dims) {
        if (d < 2) return text + ": every axis needs at least 2 samples";
        if (d > kMaxAxisSamples) return text + ": an axis may hold at most 2^31 samples";
    }
    // Each factor is at most 2^31, so the first product cannot overflow; the second is checked
    // by division.
    const int64_t slice = dims[0] * dims[1];
    if (slice > kMaxVolumeSamples || dims[2] > kMaxVolumeSamples / slice)
        return text + ": a volume may hold at most 2^48 samples";
    return "";
}

struct VolumeInfo {
    Dims3 dims{0, 0, 0};
    ScalarType type = ScalarType::U8;
    glm::dvec3 spacing{1.0, 1.0, 1.0};
    glm::dvec3 origin{0.0, 0.0, 0.0};
    // Columns: the unit LPS directions of the i, j and k axes (core/orientation.h checks them:
    // finite, not singular; not necessarily orthogonal). Identity when the input said nothing
    // of its orientation, which hasOrientation tells apart from an input that said "identity".
    glm::dmat3 direction{1.0};
    bool hasOrientation = false;

    // Sizes: throw std::overflow_error rather than wrap (dims beyond the limits above).
    int64_t sliceSamples() const { return checkedMul(dims[0], dims[1]); }
    int64_t sampleCount() const { return checkedMul(sliceSamples(), dims[2]); }
    uint64_t byteSize() const { return checkedMul(uint64_t(sampleCount()), uint64_t(scalarSize(type))); }
    // The affine map from sample coordinates (i, j, k) to world coordinates.
    glm::dmat4 gridToWorld() const {
        glm::dmat4 m(1.0);
        for (int k = 0; k < 3; ++k) {
            m[k][k] = spacing[k];
            m[3][k] = origin[k];
        }
        return m;
    }
    // World position of the last sample: the volume's bounds are [origin, worldMax()].
    glm::dvec3 worldMax() const {
        return origin + glm::dvec3(dims[0] - 1, dims[1] - 1, dims[2] - 1) * spacing;
    }
};

}  // namespace vdiso
