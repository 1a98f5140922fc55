#include "core/mesh.h"

#include <vector>

#include <glm/geometric.hpp>

namespace vdiso {

double surfaceArea(const TriangleMesh& mesh) {
    double area = 0;
    for (size_t t = 0; t < mesh.triangleCount(); ++t) {
        const glm::dvec3 a(mesh.positions[mesh.indices[3 * t]]);
        const glm::dvec3 b(mesh.positions[mesh.indices[3 * t + 1]]);
        const glm::dvec3 c(mesh.positions[mesh.indices[3 * t + 2]]);
        area += 0.5 * glm::length(glm::cross(b - a, c - a));
    }
    return area;
}

void dropUnreferencedVertices(TriangleMesh& mesh, uint32_t fromVertex) {
    const size_t first = size_t(fromVertex - mesh.firstVertex);
    if (first >= mesh.positions.size()) return;
    constexpr uint32_t kUnused = UINT32_MAX;
    std::vector<uint32_t> renumbered(mesh.positions.size() - first, kUnused);
    for (const uint32_t v : mesh.indices)
        if (v >= fromVertex) renumbered[v - fromVertex] = 0;
    uint32_t next = fromVertex;
    for (size_t k = 0; k < renumbered.size(); ++k) {
        if (renumbered[k] == kUnused) continue;
        const size_t to = next - mesh.firstVertex;
        mesh.positions[to] = mesh.positions[first + k];
        mesh.normals[to] = mesh.normals[first + k];
        renumbered[k] = next++;
    }
    mesh.positions.resize(next - mesh.firstVertex);
    mesh.normals.resize(next - mesh.firstVertex);
    for (uint32_t& v : mesh.indices)
        if (v >= fromVertex) v = renumbered[v - fromVertex];
}

}  // namespace vdiso
