// Writing extraction output, the format chosen by the file's extension:
//   .ply  binary little-endian PLY: positions, normals, faces
//   .obj  OBJ: v, vn, f with shared indices
//   .stl  binary STL: one facet normal and three corners per triangle (io/mesh/stl_writer.h)
//   .glb  glTF 2.0 binary: one indexed mesh with normals, optionally meshopt-compressed
//         (io/mesh/glb_writer.h)
//   .vtp  VTK XML PolyData, raw appended data: points, normals, polygons (io/mesh/vtp_writer.h)
// Vertices are written as the mesh holds them (welded by the extractors), through an optional
// SpaceTransform (core/orientation.h; vdiso extract gives volumeToPhysical, so that meshes land
// in the patient's LPS space as 3D Slicer and ITK place them): positions and normals mapped,
// winding reversed when it mirrors, in every format and for streamed pieces alike. Files appear only
// when complete (AtomicOutputFile); `overwrite` allows replacing an existing file. Throws
// IoError naming the file.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "core/mesh.h"
#include "core/orientation.h"

namespace vdiso {

enum class MeshFormat { Ply, Obj, Stl, Glb, Vtp };

// From the name's extension; throws IoError for anything else, listing the accepted ones.
MeshFormat meshFormatFor(const std::string& path);

class MeshFormatWriter;

// A mesh file written piece by piece as extraction streams it (a MeshSink). Memory holds no
// more than the piece being appended (but for a compressed GLB, which finish() encodes whole:
// see io/mesh/glb_writer.h): what a format lists after the vertices goes to side files next to the
// output, which finish() appends before writing the header with the final counts. Pieces must
// arrive in vertex order (part.firstVertex == vertices appended so far). `compress` applies
// EXT_meshopt_compression to a .glb; for another format it is an error. `transform` maps every
// piece before it is written (the identity: as given).
class MeshFileWriter final : public MeshSink {
public:
    MeshFileWriter(const std::string& path, bool overwrite, bool compress = false,
                   const SpaceTransform& transform = {});
    ~MeshFileWriter() override;
    void append(const TriangleMesh& part) override;
    // Completes the file, renames it into place and removes the side files; call once, last.
    // Without finish(), nothing is left behind.
    void finish();
    uint64_t vertices() const { return mVertices; }
    uint64_t triangles() const { return mTriangles; }

private:
    std::unique_ptr<MeshFormatWriter> mWriter;
    SpaceTransform mTransform;
    TriangleMesh mTransformed;  // the piece mapped by mTransform, reused across pieces
    uint64_t mVertices = 0, mTriangles = 0;
};

// The whole mesh at once (through MeshFileWriter).
void writeMesh(const std::string& path, const TriangleMesh& mesh, bool overwrite,
               bool compress = false, const SpaceTransform& transform = {});

// The binary PLY layout of .ply meshes, for writers that place the records themselves
// (mpi/collective_mesh.h): a header of exactly kPlyHeaderBytes (padded by a comment, so the
// counts' digits do not move what follows), then one record per vertex (position, normal: six
// little-endian floats), then one per triangle (a uchar 3 and three little-endian u32 indices).
constexpr size_t kPlyHeaderBytes = 512, kPlyVertexBytes = 24, kPlyFaceBytes = 13;
std::string plyMeshHeader(uint64_t vertices, uint64_t triangles);
// The records of `part`'s vertices, and of its triangles (indices as they are), end to end.
std::vector<unsigned char> plyVertexRecords(const TriangleMesh& part);
std::vector<unsigned char> plyFaceRecords(const TriangleMesh& part);

// Points with normals as a PLY vertex list (SAGE's sub-pixel points), mapped by `transform`.
void writePointsPly(const std::string& path, const PointSet& points, bool overwrite,
                    const SpaceTransform& transform = {});

}  // namespace vdiso
