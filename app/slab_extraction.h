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
#include <cmath>
#include <functional>
#include <optional>
#include <span>
#include <vector>

#include "app/array_brick_source.h"
#include "core/extract/extract_full.h"
#include "core/extract/extract_stats.h"
#include "core/kernel/edge_vertex_map.h"
#include "core/mesh.h"
#include "core/progress.h"
#include "io/readers/slice_reader.h"

namespace vdiso {

struct SlabExtractOptions {
    FullExtractOptions extract;  // iso, metaCellSize, threads (sink, brickSink, bricks: not taken)
    int brickSize = 32;
    // When set, only these bricks (increasing ids; none at all when empty) are meshed, the
    // others' samples read all the same: the triangles of their cells, as FullExtractOptions::
    // bricks gives them of an array held whole (the same arrays).
    std::optional<std::vector<int64_t>> onlyBricks;
    // Called after each layer, with its slices (rows [firstRow, firstRow + rows.dims[2]) of the
    // volume, in the store type) and the positions of the vertices it added to the output, in
    // their order: for what needs the samples at the vertices while they are held.
    std::function<void(const StridedSamples& rows, int64_t firstRow, std::span<const glm::vec3> added)> layerDone;
};

// A run of layers extracted alone (what one worker of a cluster meshes): its mesh, vertices
// numbered from 0 in the order a process extracting everything numbers them (those it shares
// with the runs before and after included), and its border vertices on the faces it shares
// with them (edge key -> its number), which joinSlabParts welds by.
struct SlabPart {
    TriangleMesh mesh;
    EdgeVertexMap border;
    ExtractStats stats;
    BrickRange range = kNoRange;  // of the run's samples (NaN left out)
};

struct SlabExtractResult {
    ExtractStats stats;
    BrickRange range = kNoRange;  // of the volume's samples (NaN left out)
};

// The range of the samples of `slices` (NaN left out; {+inf, -inf} for none), read once in
// order as extractSlabs reads them, measured on `threads` threads. Progress from 0 to 1.
BrickRange sliceRange(SliceReader& slices, int brickSize, int threads, const ProgressFn& progress = {});

// Layers [firstLayer, endLayer) of the volume of `slices`, whose reader starts at the first
// layer's first slice (its ghost below included: firstLayer * B - 1, or 0) and is read up to the
// last layer's ghosts above. Progress from 0 to 1 over the run.
SlabPart extractSlabPart(SliceReader& slices, const SlabExtractOptions& options, int64_t firstLayer,
                         int64_t endLayer, const ProgressFn& progress = {});

// Joins parts of consecutive runs of layers that cover the volume, in order, into `mesh` (the
// mesh extractSlabs makes, vertex numbers included), moving from them; `values`, when not empty,
// one array per part with a value per vertex, are joined alike into `joinedValues`. Throws
// std::invalid_argument for values that do not match their parts.
void joinSlabParts(std::span<SlabPart> parts, std::span<std::vector<float>> values, TriangleMesh& mesh,
                   std::vector<float>* joinedValues);

// Reads every slice of `slices` once, in order, and appends the surface to `mesh` (which must
// be empty). Progress runs from 0 to 1 over the layers; throws what the reader throws.
SlabExtractResult extractSlabs(SliceReader& slices, const SlabExtractOptions& options, TriangleMesh& mesh,
                               const ProgressFn& progress = {});

}  // namespace vdiso
