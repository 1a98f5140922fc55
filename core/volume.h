// What a volume is, independent of where its samples live.
//
// A volume is a grid of dims[0] x dims[1] x dims[2] samples (x fastest). Sample (i,j,k) sits at
// origin + (i,j,k) * spacing in world units. Cells are the (dims-1) cubes between samples.
#pragma once

#include <array>
#include <cstdint>

#include <glm/mat4x4.hpp>
#include <glm/vec3.hpp>

#include "core/scalar_type.h"

namespace vdiso {

using Dims3 = std::array<int64_t, 3>;

struct VolumeInfo {
    Dims3 dims{0, 0, 0};
    ScalarType type = ScalarType::U8;
    glm::dvec3 spacing{1.0, 1.0, 1.0};
    glm::dvec3 origin{0.0, 0.0, 0.0};

    int64_t sliceSamples() const { return dims[0] * dims[1]; }
    int64_t sampleCount() const { return dims[0] * dims[1] * dims[2]; }
    uint64_t byteSize() const { return uint64_t(sampleCount()) * scalarSize(type); }
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
