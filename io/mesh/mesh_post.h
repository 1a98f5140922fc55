// vdiso extract's post-processing of a full extraction (--smooth, --decimate, --largest,
// --min-piece) on surfaces larger than memory.
//
// PostProcessedMesh takes the surface brick by brick (a BrickMeshSink) and spools it, slab by
// slab of bricks, to side files beside the output. finish() then reads the slabs back: once to
// find the connected pieces when pieces are to be removed (core/mesh_post/mesh_pieces.h), once to smooth,
// decimate and hand them (core/mesh_post/mesh_slabs.h) to a MeshSink, a MeshFileWriter as a rule.
// Memory holds a batch of slabs shaped at once (two per thread) with the slabs around them that
// smoothing reaches, and the pieces' table, never the whole surface. The side
// files go with the object, whatever happens.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "core/brick_layout.h"
#include "core/extract/extract_full.h"
#include "core/mesh_post/mesh_slabs.h"
#include "core/progress.h"
#include "io/mesh/mesh_output.h"

namespace vdiso {

struct MeshPostStats {
    uint64_t trianglesIn = 0, verticesIn = 0;    // as extracted
    uint64_t trianglesOut = 0, verticesOut = 0;  // as written
    uint64_t pieces = 0, piecesKept = 0;         // 0, 0 unless pieces were removed
    uint64_t largestPieceTriangles = 0;
    uint64_t spoolBytes = 0;                     // the side files' size
    int slabs = 0, haloSlabs = 0;
    uint64_t largestWindowTriangles = 0;  // the most triangles a window held
    double piecesSeconds = 0, finishSeconds = 0;
};

class PostProcessedMesh final : public BrickMeshSink {
public:
    // Side files go beside `outputPath` (named after it where they need names). `layout`: the
    // bricks the extraction numbers. The result goes to `out`.
    PostProcessedMesh(const std::string& outputPath, const BrickLayout& layout, const MeshPostOptions& options,
                      MeshSink& out);
    void appendBrick(int64_t id, const TriangleMesh& part) override;
    // Removes pieces, smooths, decimates and hands the result to the sink, piece by piece; call
    // once, after the extraction.
    MeshPostStats finish(const ProgressFn& progress = {});

private:
    struct Slab {
        uint32_t firstVertex = 0, vertexCount = 0;
        uint64_t firstIndex = 0, indexCount = 0;
    };
    // Slab k as spooled, its triangles those of kept pieces (`keep`, by piece label, if set).
    TriangleMesh readSlab(int k, const std::vector<uint8_t>* keep);
    void startSlabs(int64_t untilZ);

    BrickLayout mLayout;
    MeshPostOptions mOptions;
    MeshSink& mOut;
    SideFile mVertices, mIndices;  // (position, normal) per vertex; 3 indices per triangle
    std::optional<SideFile> mLabels;  // a piece label per triangle
    std::vector<Slab> mSlabs;         // one per brick z coordinate seen so far
};

}  // namespace vdiso
