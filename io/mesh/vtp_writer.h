// VTK XML PolyData (.vtp) output (behind MeshFileWriter, io/mesh/mesh_writer.h), as ParaView reads
// it: version 1.0, little-endian, UInt64 block headers, every array in raw appended data:
// Points (Float32, 3), PointData Normals (Float32, 3, the active normals), Polys connectivity
// and offsets (Int64; offsets are each triangle's end in the connectivity, 3, 6, 9, ...).
//
// Streamed: the XML header has a fixed length (padded by a comment) and is written last over a
// placeholder; the points follow it as they come; normals and connectivity go to side files
// that finish() appends, then the offsets. Memory holds one piece.
#pragma once

#include <memory>
#include <string>

namespace vdiso {

class MeshFormatWriter;

std::unique_ptr<MeshFormatWriter> makeVtpWriter(const std::string& path, bool overwrite);

}  // namespace vdiso
