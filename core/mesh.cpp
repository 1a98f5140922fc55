#include "core/mesh.h"

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

}  // namespace vdiso
