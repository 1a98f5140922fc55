// Binary STL output (behind MeshFileWriter, io/mesh/mesh_writer.h): an 80-byte header, the
// triangle count (u32), then per triangle its facet normal, its three corners (floats) and a
// zero u16. The facet normal is the triangle's, normalised (counter-clockwise corners, as the
// mesh holds them); for a triangle with no area, the mean of its vertices' normals.
//
// Streamed: each piece's triangles are written as they come and the count at finish(). A
// triangle may use a vertex of an earlier piece (welded across a seam); those are kept in a side
// file and read back when needed, so memory holds one piece. More than 2^32 - 1 triangles do
// not fit the count: an IoError.
#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "core/mesh.h"

namespace vdiso {

class MeshFormatWriter;

std::unique_ptr<MeshFormatWriter> makeStlWriter(const std::string& path, bool overwrite);

// The layout, for writers that place the records themselves (mpi/collective_mesh.h): the header
// (80 bytes and the count) and kStlTriangleBytes per triangle.
constexpr size_t kStlHeaderBytes = 84, kStlTriangleBytes = 50;
std::array<unsigned char, kStlHeaderBytes> stlHeader(uint32_t triangles);
// The records of `part`'s triangles, whose indices refer to its own vertices, end to end.
std::vector<unsigned char> stlTriangleRecords(const TriangleMesh& part);

}  // namespace vdiso
