// The octree's full extraction (core/extract/extract_full.h) of a volume read once, in order,
// from a SliceReader, holding one layer of bricks at a time (B + 3 slices) instead of the whole
// volume: what meshes an array larger than memory (a Dask or Zarr array from Python).
//
// Each layer of bricks (brick coordinate z) is extracted as a part (FullExtractOptions::bricks)
// on options.threads threads from an ArrayBrickSource over the slices it needs; its vertices on
// the face it shares with the layer before are that layer's (welded by edge key), the others
// are numbered next. The result is the mesh extractOctree makes of the whole volume held in
// memory, vertex numbers included: a process extracting everything numbers the layers' new
// vertices one layer after another. Memory: the output, one layer's slices and one layer's
// part.
#pragma once

#include <cstdint>
#include <functional>
#include <span>

#include "app/array_brick_source.h"
#include "core/extract/extract_full.h"
#include "core/extract/extract_stats.h"
#include "core/mesh.h"
#include "core/progress.h"
#include "io/readers/slice_reader.h"

namespace vdiso {

struct SlabExtractOptions {
    FullExtractOptions extract;  // iso, metaCellSize, threads (sink, brickSink, bricks: not taken)
    int brickSize = 32;
    // Called after each layer, with its slices (rows [firstRow, firstRow + rows.dims[2]) of the
    // volume, in the store type) and the positions of the vertices it added to the output, in
    // their order: for what needs the samples at the vertices while they are held.
    std::function<void(const StridedSamples& rows, int64_t firstRow, std::span<const glm::vec3> added)> layerDone;
};

struct SlabExtractResult {
    ExtractStats stats;
    BrickRange range{INFINITY, -INFINITY};  // of the volume's samples (NaN left out)
};

// The range of the samples of `slices` (NaN left out; {+inf, -inf} for none), read once in
// order as extractSlabs reads them, measured on `threads` threads. Progress from 0 to 1.
BrickRange sliceRange(SliceReader& slices, int brickSize, int threads, const ProgressFn& progress = {});

// Reads every slice of `slices` once, in order, and appends the surface to `mesh` (which must
// be empty). Progress runs from 0 to 1 over the layers; throws what the reader throws.
SlabExtractResult extractSlabs(SliceReader& slices, const SlabExtractOptions& options, TriangleMesh& mesh,
                               const ProgressFn& progress = {});

}  // namespace vdiso
