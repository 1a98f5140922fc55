// A range of a mesh's final arrays that one chunk of a full extraction writes in place, its
// size counted beforehand (core/extract/extract_in_place.h): vertices numbered firstVertex
// onwards at positions/normals, triangles at indices. The kernel (core/kernel/brick_kernel.h)
// writes into it through addVertex and addTriangle, as it appends to a TriangleMesh.
//
// A brick writes only the vertices it owns (core/kernel/edge_vertex_map.h, EdgeOwnership). A
// vertex its owner makes in another chunk, which this chunk cannot see, gets a placeholder
// number (kPlaceholderTop, then down), recorded with its edge key, position and normal (for a
// store whose bricks disagree on the samples they share, where the owner may not make it); each
// index that refers to it is recorded too, for the caller to set once every chunk is written.
// Writing past the counted size throws std::logic_error: the count and the kernel disagree.
#pragma once

#include <cstddef>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <vector>

#include <glm/vec3.hpp>

#include "core/kernel/edge_vertex_map.h"

namespace vdiso {

struct PlacedMesh {
    static constexpr uint32_t kPlaceholderTop = UINT32_MAX - 1;  // UINT32_MAX: "none" in maps

    glm::vec3* positions = nullptr;
    glm::vec3* normals = nullptr;
    uint32_t* indices = nullptr;
    uint32_t firstVertex = 0;  // global number of positions[0]
    size_t vertexCapacity = 0, indexCapacity = 0;
    size_t vertices = 0, indexCount = 0;  // written so far
    const EdgeOwnership* ownership = nullptr;  // which brick makes a shared edge's vertex

    struct Placeholder {
        uint64_t key;
        glm::vec3 position, normal;
    };
    struct PlaceholderRef {
        size_t index;      // into the whole mesh's indices, from this range's start
        uint32_t placeholder;
    };
    std::vector<Placeholder> placeholders;  // number kPlaceholderTop - k is placeholders[k]
    std::vector<PlaceholderRef> refs;

    uint32_t nextVertex() const { return firstVertex + uint32_t(vertices); }
    void addVertex(const glm::vec3& position, const glm::vec3& normal) {
        if (vertices == vertexCapacity) overflow("vertices");
        positions[vertices] = position;
        normals[vertices] = normal;
        ++vertices;
    }
    uint32_t addPlaceholder(uint64_t key, const glm::vec3& position, const glm::vec3& normal) {
        placeholders.push_back({key, position, normal});
        mLowestPlaceholder = kPlaceholderTop - uint32_t(placeholders.size() - 1);
        return mLowestPlaceholder;
    }
    void addTriangle(uint32_t a, uint32_t b, uint32_t c) {
        if (indexCount + 3 > indexCapacity) overflow("triangles");
        uint32_t* to = indices + indexCount;
        to[0] = a;
        to[1] = b;
        to[2] = c;
        if ((a | b | c) >= mLowestPlaceholder) [[unlikely]]
            for (int k = 0; k < 3; ++k)
                if (to[k] >= mLowestPlaceholder) refs.push_back({indexCount + size_t(k), kPlaceholderTop - to[k]});
        indexCount += 3;
    }
    bool isPlaceholder(uint32_t v) const { return v >= mLowestPlaceholder && v <= kPlaceholderTop; }

private:
    // Placeholders are numbered from the top: a vertex number at least this is one.
    uint32_t mLowestPlaceholder = UINT32_MAX;
    [[noreturn]] static void overflow(const char* what) {
        throw std::logic_error(std::string("full extraction: the kernel wrote more ") + what +
                               " than were counted for its chunk");
    }
};

}  // namespace vdiso
