#include "core/mesh.h"

#include <algorithm>
#include <cmath>
#include <utility>
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

void orientNormalsToFaces(TriangleMesh& mesh, size_t firstTriangle, uint32_t firstOwnVertex) {
    const size_t end = mesh.indices.size();
    if (3 * firstTriangle >= end) return;
    uint32_t hi = 0;
    for (size_t i = 3 * firstTriangle; i < end; ++i) hi = std::max(hi, mesh.indices[i]);
    // The vertices these triangles' brick made are numbered from firstOwnVertex: their sums
    // are kept in an array; a few welded from earlier bricks (a brick's seams), which would
    // stretch an array over every vertex between, go to a list sorted by vertex. Each vertex's
    // sum is added up in triangle order either way. (The array had been as long as the
    // triangles' corners, several times the vertices of their own.)
    const uint32_t dense = std::min(firstOwnVertex, hi + 1);
    std::vector<glm::vec3> faces(size_t(hi) + 1 - size_t(dense), glm::vec3(0.0f));
    std::vector<std::pair<uint32_t, glm::vec3>> far;  // (vertex, a triangle's face) below `dense`
    auto held = [&](uint32_t v) { return size_t(v - mesh.firstVertex); };
    for (size_t i = 3 * firstTriangle; i < end; i += 3) {
        const uint32_t* t = &mesh.indices[i];
        const glm::vec3 a = mesh.positions[held(t[0])], b = mesh.positions[held(t[1])], c = mesh.positions[held(t[2])];
        const glm::vec3 n = glm::cross(b - a, c - a);  // twice the area, along the face normal
        for (int k = 0; k < 3; ++k) {
            if (t[k] >= dense) faces[t[k] - dense] += n;
            else far.emplace_back(t[k], n);
        }
    }
    auto orient = [&](uint32_t v, const glm::vec3& f) {
        glm::vec3& n = mesh.normals[held(v)];
        if (glm::dot(n, f) < 0.0f) n = glm::normalize(f);
    };
    for (size_t k = 0; k < faces.size(); ++k) orient(dense + uint32_t(k), faces[k]);
    std::stable_sort(far.begin(), far.end(), [](const auto& x, const auto& y) { return x.first < y.first; });
    for (size_t k = 0; k < far.size();) {
        const uint32_t v = far[k].first;
        glm::vec3 f(0.0f);
        for (; k < far.size() && far[k].first == v; ++k) f += far[k].second;
        orient(v, f);
    }
}

size_t splitVerticesFacingAway(TriangleMesh& mesh, size_t firstTriangle, const glm::vec3& eye) {
    size_t copies = 0;
    const size_t end = mesh.indices.size();
    for (size_t i = 3 * firstTriangle; i < end; i += 3) {
        uint32_t* t = &mesh.indices[i];
        const glm::vec3 a = mesh.positions[t[0] - mesh.firstVertex];
        const glm::vec3 face = glm::cross(mesh.positions[t[1] - mesh.firstVertex] - a,
                                          mesh.positions[t[2] - mesh.firstVertex] - a);
        const float area2 = glm::dot(face, face);  // the length's square: its root only for a copy
        if (!(area2 > 0.0f)) continue;
        const float side = glm::dot(face, eye - a) >= 0.0f ? 1.0f : -1.0f;  // back: normals turned
        for (int k = 0; k < 3; ++k) {
            const size_t v = t[k] - mesh.firstVertex;
            const glm::vec3 p = mesh.positions[v];
            if (glm::dot(side * mesh.normals[v], eye - p) >= 0.0f) continue;
            mesh.positions.push_back(p);
            mesh.normals.push_back(face / std::sqrt(area2));
            t[k] = mesh.nextVertex() - 1;
            ++copies;
        }
    }
    return copies;
}

}  // namespace vdiso
