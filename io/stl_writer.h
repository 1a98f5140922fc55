// Binary STL output (behind MeshFileWriter, io/mesh_writer.h): an 80-byte header, the
// triangle count (u32), then per triangle its facet normal, its three corners (floats) and a
// zero u16. The facet normal is the triangle's, normalised (counter-clockwise corners, as the
// mesh holds them); for a triangle with no area, the mean of its vertices' normals.
//
// Streamed: each piece's triangles are written as they come and the count at finish(). A
// triangle may use a vertex of an earlier piece (welded across a seam); those are kept in a side
// file and read back when needed, so memory holds one piece. More than 2^32 - 1 triangles do
// not fit the count: an IoError.
#pragma once

#include <memory>
#include <string>

namespace vdiso {

class MeshFormatWriter;

std::unique_ptr<MeshFormatWriter> makeStlWriter(const std::string& path, bool overwrite);

}  // namespace vdiso
