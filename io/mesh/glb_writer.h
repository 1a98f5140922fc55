// glTF 2.0 binary (.glb) output (behind MeshFileWriter, io/mesh/mesh_writer.h): one scene, one node,
// one mesh of one indexed triangle primitive with POSITION (with its min and max) and NORMAL
// (float VEC3) and u32 indices, in buffer 0, the GLB's BIN chunk. The JSON chunk is padded
// with spaces and the BIN chunk with zeros to 4 bytes. A mesh without triangles is a scene with
// one empty node and no BIN chunk. A GLB holds at most 4 GiB: a larger mesh is an IoError.
//
// With `compress`, the three buffer views are EXT_meshopt_compression views (ATTRIBUTES for the
// vertex streams, TRIANGLES for the indices; meshoptimizer's codecs) of a fallback buffer
// without data, and the extension is required. Vertices and triangles keep the extraction's
// order (not reordered for the codecs); the index codec may start a triangle at another of its
// corners, keeping its winding.
//
// Memory: the positions, normals and indices are streamed to three side files and copied into
// place by finish(), so memory holds one piece; compressed, finish() reads each stream back
// whole to encode it, so memory then holds one stream (12 bytes a vertex, or 12 a triangle)
// and the encoded data.
#pragma once

#include <memory>
#include <string>

namespace vdiso {

class MeshFormatWriter;

std::unique_ptr<MeshFormatWriter> makeGlbWriter(const std::string& path, bool overwrite,
                                                bool compress);

}  // namespace vdiso
