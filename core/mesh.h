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
#include <new>
#include <memory>
#include <type_traits>
#include <utility>
#include <vector>

#include <glm/vec3.hpp>

#include "core/huge_pages.h"

namespace vdiso {

template <class T>
using MeshArray = std::vector<T, UninitializedAllocator<T>>;

struct TriangleMesh {
    MeshArray<glm::vec3> positions;
    MeshArray<glm::vec3> normals;
    MeshArray<uint32_t> indices;  // 3 per triangle, global vertex numbers
    // Global number of positions[0]: non-zero when earlier vertices were handed to a MeshSink
    // and dropped (indices still count them), so welded references stay valid while streaming.
    uint32_t firstVertex = 0;

    size_t vertexCount() const { return positions.size(); }  // vertices held
    size_t triangleCount() const { return indices.size() / 3; }
    uint32_t nextVertex() const { return firstVertex + uint32_t(positions.size()); }
    // What the extraction kernel writes through (core/kernel/brick_kernel.h), as it writes
    // into a PlacedMesh (core/kernel/placed_mesh.h).
    void addVertex(const glm::vec3& position, const glm::vec3& normal) {
        positions.push_back(position);
        normals.push_back(normal);
    }
    void addTriangle(uint32_t a, uint32_t b, uint32_t c) { indices.insert(indices.end(), {a, b, c}); }
    void clear() {
        positions.clear();
        normals.clear();
        indices.clear();
    }
};

// Where streamed extraction output goes (a file writer in io/, a test's collector). append()
// receives the vertices numbered part.firstVertex onwards and triangles that may refer to any
// vertex appended so far or in this part; the caller then drops them (see drainInto).
class MeshSink {
public:
    virtual ~MeshSink() = default;
    virtual void append(const TriangleMesh& part) = 0;
};

// A MeshSink that appends what it receives to a mesh held whole (firstVertex 0).
class MeshAppender final : public MeshSink {
public:
    explicit MeshAppender(TriangleMesh& mesh) : mMesh(mesh) {}
    void append(const TriangleMesh& part) override {
        mMesh.positions.insert(mMesh.positions.end(), part.positions.begin(), part.positions.end());
        mMesh.normals.insert(mMesh.normals.end(), part.normals.begin(), part.normals.end());
        mMesh.indices.insert(mMesh.indices.end(), part.indices.begin(), part.indices.end());
    }

private:
    TriangleMesh& mMesh;
};

// Sum of the triangles' areas (in double), in world units squared. Indices must refer to the
// vertices the mesh holds (firstVertex == 0).
double surfaceArea(const TriangleMesh& mesh);

// Turns the normal of each vertex of triangles [firstTriangle, triangleCount()) that points
// against those triangles (against the sum of their area-weighted face normals, which the
// winding orients) to that sum's direction. A gradient normal points the wrong way where a part
// is about a cell thin and central differences span it: on coarse levels of detail such
// vertices were drawn nearly black. Indices must refer to vertices the mesh holds; the
// triangles' own vertices (their brick's) are numbered from firstOwnVertex, and few are not.
void orientNormalsToFaces(TriangleMesh& mesh, size_t firstTriangle, uint32_t firstOwnVertex);

// Seen from `eye`, lit from it with two-sided lighting (a triangle's normals turned for its
// back), each vertex of triangles [firstTriangle, triangleCount()) whose normal would face away
// from the eye in that triangle (a fold of a coarse surface, where one vertex joins triangles
// facing the eye and facing away) gets a copy of its own for that triangle, with the
// triangle's face normal, which faces the eye once turned. Such vertices were drawn black where
// the full-resolution surface is lit. Returns the copies made (appended to the mesh).
size_t splitVerticesFacingAway(TriangleMesh& mesh, size_t firstTriangle, const glm::vec3& eye);

// Hands what `mesh` holds to the sink and drops it, keeping the global vertex numbering.
inline void drainInto(MeshSink& sink, TriangleMesh& mesh) {
    sink.append(mesh);
    mesh.firstVertex = mesh.nextVertex();
    mesh.clear();
}

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
