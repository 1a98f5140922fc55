// Writing extraction output: binary little-endian PLY (positions, normals, faces) and OBJ
// (v, vn, f with shared indices). Vertices are written as the mesh holds them (welded by the
// extractors). Files appear only when complete (AtomicOutputFile); `overwrite` allows
// replacing an existing file. Throws IoError naming the file.
#pragma once

#include <string>

#include "core/mesh.h"

namespace vdiso {

enum class MeshFormat { Ply, Obj };

// From the name: .ply or .obj; throws IoError for anything else.
MeshFormat meshFormatFor(const std::string& path);

void writeMesh(const std::string& path, const TriangleMesh& mesh, bool overwrite);

// Points with normals as a PLY vertex list (SAGE's sub-pixel points).
void writePointsPly(const std::string& path, const PointSet& points, bool overwrite);

}  // namespace vdiso
