// Writing extraction output: binary little-endian PLY (positions, normals, faces) and OBJ
// (v, vn, f with shared indices). Vertices are written as the mesh holds them (welded by the
// extractors). Files appear only when complete (AtomicOutputFile); `overwrite` allows
// replacing an existing file. Throws IoError naming the file.
#pragma once

#include <cstdint>
#include <memory>
#include <string>

#include "core/mesh.h"

namespace vdiso {

enum class MeshFormat { Ply, Obj };

// From the name: .ply or .obj; throws IoError for anything else.
MeshFormat meshFormatFor(const std::string& path);

// A mesh file written piece by piece as extraction streams it (a MeshSink): vertex records go
// to the output file as they come, face records to a side file next to it, and finish()
// appends the faces and writes the header with the final counts. Memory holds no more than
// the piece being appended. Both formats list all vertices before all faces, hence the side
// file. Pieces must arrive in vertex order (part.firstVertex == vertices appended so far).
class MeshFileWriter final : public MeshSink {
public:
    MeshFileWriter(const std::string& path, bool overwrite);
    ~MeshFileWriter() override;
    void append(const TriangleMesh& part) override;
    // Completes the file, renames it into place and removes the side file; call once, last.
    // Without finish(), nothing is left behind.
    void finish();
    uint64_t vertices() const { return mVertices; }
    uint64_t triangles() const { return mTriangles; }

private:
    struct Files;
    std::unique_ptr<Files> mFiles;
    MeshFormat mFormat;
    uint64_t mVertices = 0, mTriangles = 0;
};

// The whole mesh at once (through MeshFileWriter).
void writeMesh(const std::string& path, const TriangleMesh& mesh, bool overwrite);

// Points with normals as a PLY vertex list (SAGE's sub-pixel points).
void writePointsPly(const std::string& path, const PointSet& points, bool overwrite);

}  // namespace vdiso
