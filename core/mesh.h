// Extraction output, struct-of-arrays: what the extractors append to and the writers and the
// renderer read.
//
// Triangles: positions and normals per vertex (world units; normals unit length, pointing from
// the side above the isovalue towards the side below it, i.e. along minus the gradient, which
// is outward for a dense object such as bone in CT), and three vertex indices per triangle,
// counter-clockwise seen from the side the normal points to.
// Points (SAGE §3.3): a position and a normal each, for sub-pixel parts of the surface.
#pragma once

#include <cstdint>
#include <vector>

#include <glm/vec3.hpp>

namespace vdiso {

struct TriangleMesh {
    std::vector<glm::vec3> positions;
    std::vector<glm::vec3> normals;
    std::vector<uint32_t> indices;  // 3 per triangle

    size_t vertexCount() const { return positions.size(); }
    size_t triangleCount() const { return indices.size() / 3; }
    void clear() {
        positions.clear();
        normals.clear();
        indices.clear();
    }
};

struct PointSet {
    std::vector<glm::vec3> positions;
    std::vector<glm::vec3> normals;

    size_t size() const { return positions.size(); }
    void clear() {
        positions.clear();
        normals.clear();
    }
};

}  // namespace vdiso
