// A full extraction into a mesh held whole or streamed, each vertex and triangle written once, into its
// final place (Flying Edges' passes, over bricks instead of rows):
//   1. count: each brick's triangles and the vertices it owns (an edge's vertex belongs to the
//      lowest-numbered extracted brick on it: EdgeOwnership), by classification alone;
//   2. prefix sums of the counts, cut into chunks of about equal triangles, and one allocation
//      of the exact size (a MeshAllocationError naming it when that fails, the mesh untouched);
//   3. emit: the chunks in parallel, each brick writing its vertices and triangles at its
//      chunk's offsets (core/kernel/placed_mesh.h), welding within the chunk through its seam
//      map; a vertex whose owner is in an earlier chunk gets a placeholder, set from the
//      owner chunk's map once every chunk is written.
// Streamed to a sink, rounds of bricks are counted, written into the same arrays and handed
// over in turn. Nothing is merged or copied; each thread first-touches the pages it writes.
// The mesh is the one a single thread appending brick by brick makes, vertex numbers
// included, for any thread count: the owner of an edge is the first brick, in id order, to
// make its vertex.
#pragma once

#include <cstdint>
#include <new>
#include <span>
#include <string>

#include "core/extract/extract_full.h"
#include "core/extract/extract_stats.h"
#include "core/kernel/brick_extractor.h"
#include "core/mesh.h"
#include "core/progress.h"

namespace vdiso {

// One brick of a full extraction: with `metaCells` empty, every meta-cell whose range holds the
// isovalue (the octree); otherwise those listed (NOISE's span-space query).
struct BrickItem {
    int64_t id;
    std::span<const uint32_t> metaCells;
};

// The output of a full extraction could not be allocated; what() names its size. A
// std::bad_alloc, so Python raises MemoryError.
class MeshAllocationError : public std::bad_alloc {
public:
    explicit MeshAllocationError(std::string message) : mMessage(std::move(message)) {}
    const char* what() const noexcept override { return mMessage.c_str(); }

private:
    std::string mMessage;
};

// The error for a surface of `vertices` and `triangles` that cannot be allocated: "cannot
// allocate the surface: T triangles and V vertices need N MB" (`grown`: the surface held that
// much and could not grow; `working`: it was allocated, the extraction's own memory was not).
enum class AllocationFailure { Output, Growth, Working };
MeshAllocationError meshAllocationError(uint64_t vertices, uint64_t triangles,
                                        AllocationFailure what = AllocationFailure::Output);

// Extracts `items` (increasing brick ids) on options.threads threads (the full extractions call
// it with two or more: on one, appending brick by brick writes once too, and its reads ahead
// overlap the extraction where a count would wait for them) and appends the surface to
// `mesh` (numbered from mesh.nextVertex()); options.bricks and options.borderVertices as in
// FullExtractOptions. With options.sink, the surface goes to it in rounds of about
// options.streamPieceVertices vertices, each written in place, handed over and dropped, and
// the mesh is empty at the end; options.brickSink is not taken. Progress runs from
// progressStart to 1.
// Sets stats.triangles, vertices and brickWaitSeconds; returns the kernel's counters.
KernelCounters extractInPlace(std::span<const BrickItem> items, BrickSource& source,
                              const FullExtractOptions& options, TriangleMesh& mesh,
                              ExtractStats& stats, const ProgressFn& progress, double progressStart);

}  // namespace vdiso
