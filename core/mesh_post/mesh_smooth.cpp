#include "core/mesh_post/mesh_smooth.h"

#include <algorithm>
#include <vector>

#include <glm/geometric.hpp>

namespace vdiso {

namespace {

constexpr float kLambda = 0.5f;
constexpr float kPassBand = 0.1f;
constexpr float kMu = 1.0f / (kPassBand - 1.0f / kLambda);

// Each vertex's edge neighbours, increasing, as a compressed row list: the neighbours of v are
// neighbours[first[v] .. first[v + 1]). None for a vertex on an open edge, which stays.
struct Neighbours {
    std::vector<uint32_t> first, neighbours;
};

Neighbours neighboursOf(size_t vertexCount, std::span<const uint32_t> indices) {
    // Every triangle gives each corner its two others: the incidences, counted then placed.
    std::vector<uint32_t> start(vertexCount + 1, 0);
    for (uint32_t v : indices) start[v + 1] += 2;
    for (size_t v = 0; v < vertexCount; ++v) start[v + 1] += start[v];
    std::vector<uint32_t> incident(start[vertexCount]);
    std::vector<uint32_t> fill(start.begin(), start.end() - 1);
    for (size_t t = 0; t + 2 < indices.size(); t += 3) {
        for (int c = 0; c < 3; ++c) {
            const uint32_t v = indices[t + size_t(c)];
            incident[fill[v]++] = indices[t + size_t((c + 1) % 3)];
            incident[fill[v]++] = indices[t + size_t((c + 2) % 3)];
        }
    }
    // Sorted, a neighbour appears once per triangle on the edge: once marks an open edge.
    Neighbours n;
    n.first.assign(vertexCount + 1, 0);
    n.neighbours.reserve(incident.size() / 2);
    for (size_t v = 0; v < vertexCount; ++v) {
        const auto begin = incident.begin() + start[v], end = incident.begin() + start[v + 1];
        std::sort(begin, end);
        bool open = false;
        for (auto i = begin; i != end; ++i)
            if ((i == begin || *(i - 1) != *i) && (i + 1 == end || *(i + 1) != *i)) open = true;
        if (!open)
            for (auto i = begin; i != end; ++i)
                if (i == begin || *(i - 1) != *i) n.neighbours.push_back(*i);
        n.first[v + 1] = uint32_t(n.neighbours.size());
    }
    return n;
}

}  // namespace

void smoothTaubin(std::span<glm::vec3> positions, std::span<const uint32_t> indices, int iterations) {
    if (iterations <= 0 || indices.empty()) return;
    const Neighbours n = neighboursOf(positions.size(), indices);
    std::vector<glm::vec3> next(positions.begin(), positions.end());
    for (int pass = 0; pass < 2 * iterations; ++pass) {
        const float factor = pass % 2 == 0 ? kLambda : kMu;
        for (size_t v = 0; v < positions.size(); ++v) {
            const uint32_t begin = n.first[v], end = n.first[v + 1];
            if (begin == end) continue;
            glm::vec3 sum(0.0f);
            for (uint32_t i = begin; i < end; ++i) sum += positions[n.neighbours[i]];
            next[v] = positions[v] + factor * (sum / float(end - begin) - positions[v]);
        }
        std::copy(next.begin(), next.end(), positions.begin());
    }
}

void triangleNormals(std::span<const glm::vec3> positions, std::span<const uint32_t> indices,
                     std::span<glm::vec3> normals, uint32_t first, uint32_t count) {
    std::vector<glm::vec3> sum(count, glm::vec3(0.0f));
    for (size_t t = 0; t + 2 < indices.size(); t += 3) {
        const uint32_t a = indices[t], b = indices[t + 1], c = indices[t + 2];
        const glm::vec3 area = glm::cross(positions[b] - positions[a], positions[c] - positions[a]);
        for (uint32_t v : {a, b, c})
            if (v - first < count) sum[v - first] += area;
    }
    for (uint32_t k = 0; k < count; ++k) {
        const float length = glm::length(sum[k]);
        if (length > 0.0f) normals[first + k] = sum[k] / length;
    }
}

}  // namespace vdiso
