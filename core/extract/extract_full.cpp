#include "core/clock.h"
#include "core/extract/extract_full.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <mutex>
#include <span>
#include <stdexcept>
#include <string>

#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include "core/extract/brick_prefetcher.h"
#include "core/extract/extract_in_place.h"
#include "core/extract/part_border.h"
#include "core/kernel/edge_vertex_map.h"
#include "core/kernel/iso.h"
#include "core/trees/minmax_tree.h"
#include "core/trees/span_space.h"

namespace vdiso {

namespace {

// Progress every few dozen bricks: often enough for a bar, rare enough to cost nothing.
constexpr int64_t kProgressEvery = 32;

// Chunks per thread when extracting in parallel: enough to balance uneven bricks.
constexpr size_t kChunksPerThread = 8;
// Streamed, a chunk holds at most this many bricks, and each thread extracts this many chunks a
// round: memory holds a few hundred bricks' surface, whatever the volume.
constexpr size_t kStreamedChunkBricks = 64;
constexpr size_t kStreamedChunksPerThread = 2;


// Where one brick's output ends in its chunk's mesh (vertex and index counts after it).
struct BrickEnd {
    size_t vertices, indices;
};

struct ChunkOutput {
    TriangleMesh mesh;
    EdgeVertexMap seams;
    KernelCounters counters;
    std::vector<BrickEnd> brickEnds;  // only when handing the surface over brick by brick
};

// Appends a chunk's mesh to `out`, merging its brick-face vertices with those already there.
// (Chunk meshes number their vertices from 0; `out` may have streamed earlier ones away.) With
// the chunk's brick ends, brickDone(k) follows the appending of its k-th brick's output, which
// may then be drained.
template <class BrickDone>
void mergeChunk(ChunkOutput& chunk, TriangleMesh& out, EdgeVertexMap& outSeams, BrickDone&& brickDone) {
    constexpr uint32_t kNew = UINT32_MAX;
    std::vector<uint32_t> remap(chunk.mesh.vertexCount(), kNew);
    chunk.seams.forEach([&](uint64_t key, uint32_t v) {
        const uint32_t existing = outSeams.find(key);
        if (existing != UINT32_MAX) remap[v] = existing;
    });
    // A vertex is made by the chunk's first brick using it, so a brick's triangles refer only to
    // vertices of the bricks appended before or with it.
    auto appendSpan = [&](BrickEnd begin, BrickEnd end) {
        for (size_t v = begin.vertices; v < end.vertices; ++v) {
            if (remap[v] != kNew) continue;
            remap[v] = out.nextVertex();
            out.positions.push_back(chunk.mesh.positions[v]);
            out.normals.push_back(chunk.mesh.normals[v]);
        }
        out.indices.reserve(out.indices.size() + (end.indices - begin.indices));
        for (size_t i = begin.indices; i < end.indices; ++i) out.indices.push_back(remap[chunk.mesh.indices[i]]);
    };
    if (chunk.brickEnds.empty()) {
        appendSpan({0, 0}, {chunk.mesh.vertexCount(), chunk.mesh.indices.size()});
    } else {
        BrickEnd begin{0, 0};
        for (size_t k = 0; k < chunk.brickEnds.size(); ++k) {
            appendSpan(begin, chunk.brickEnds[k]);
            brickDone(k);
            begin = chunk.brickEnds[k];
        }
    }
    chunk.seams.forEach([&](uint64_t key, uint32_t v) {
        if (outSeams.find(key) == UINT32_MAX) outSeams.insert(key, remap[v]);
    });
}

// On several threads the surface is counted, then written in place, held or streamed to a
// sink (core/extract/extract_in_place.h); on one thread, and brick by brick to post-processing,
// it goes through extractItems.
bool writesInPlace(const FullExtractOptions& options) {
    return options.threads > 1 && (options.sink || !options.brickSink);
}

int64_t brickOf(int64_t id) { return id; }

// NOISE's unit of work: one brick and the range of its active meta-cells in a shared list.
struct BrickWork {
    int64_t id;
    size_t begin, end;
};
int64_t brickOf(const BrickWork& w) { return w.id; }

// Streams the surface of `items` to options.sink or options.brickSink, or on one thread appends
// it to `mesh` (held on several threads, it is extractInPlace's): runs extractItem(extractor,
// item, samples, mesh, seams) over them on `threads` threads, acquiring each item's brick first
// (the time waited for it is counted).
template <class Item, class ExtractItem>
KernelCounters extractItems(const std::vector<Item>& items, BrickSource& source,
                            const FullExtractOptions& options, TriangleMesh& mesh,
                            ExtractStats& stats, const ProgressFn& progress,
                            double progressStart, ExtractItem&& extractItem) {
    const uint32_t firstVertex = mesh.nextVertex();
    uint64_t trianglesStreamed = 0;
    std::atomic<int64_t> waitNanoseconds{0};
    BrickMeshSink* const brickSink = options.sink ? nullptr : options.brickSink;
    auto stream = [&](bool last) {
        if (!options.sink || (!last && mesh.vertexCount() < options.streamPieceVertices)) return;
        trianglesStreamed += mesh.triangleCount();
        drainInto(*options.sink, mesh);
    };
    // Hands the mesh, brick `id`'s output alone, to the brick sink and drops it.
    auto handOverBrick = [&](int64_t id) {
        trianglesStreamed += mesh.triangleCount();
        brickSink->appendBrick(id, mesh);
        mesh.firstVertex = mesh.nextVertex();
        mesh.clear();
    };
    auto finish = [&] {
        stream(true);
        stats.triangles = trianglesStreamed + mesh.triangleCount();
        stats.vertices = mesh.nextVertex() - firstVertex;
        stats.brickWaitSeconds = double(waitNanoseconds) * 1e-9;
    };
    // A surface crossing a brick has on the order of B^2 active cells, two triangles and one
    // vertex each (the 512^3 head about 1,700 vertices a brick of 32^3, the MRI more): twice
    // that reserved up front saves the copies and fresh page faults of regrowth (reserved pages
    // that are never touched cost nothing; process wall A/B 0.94-0.98 against B^2).
    const size_t perBrick = size_t(expectedVerticesPerBrick(source.layout().brickSize));
    const size_t expectVertices = options.sink        ? options.streamPieceVertices + perBrick * 4
                                  : brickSink != nullptr ? perBrick * 4
                                                         : items.size() * perBrick;
    try {  // a hint: where the address space will not have it, the mesh grows as it is written
        mesh.indices.reserve(mesh.indices.size() + expectVertices * 6);
        mesh.positions.reserve(mesh.positions.size() + expectVertices);
        mesh.normals.reserve(mesh.positions.capacity());
    } catch (const std::bad_alloc&) {
    }
    auto report = [&](size_t done) {
        // No items (an isovalue outside the volume's range) is all done, not 0/0.
        const double part = items.empty() ? 1.0 : double(done) / double(items.size());
        if (progress) progress(progressStart + (1.0 - progressStart) * part);
    };
    auto acquireTimed = [&](const Item& item) {
        const auto start = Clock::now();
        BrickHandle brick = source.acquire(brickOf(item));
        waitNanoseconds += std::chrono::duration_cast<std::chrono::nanoseconds>(Clock::now() - start).count();
        return brick;
    };
    std::vector<int64_t> bricks(items.size());
    for (size_t i = 0; i < items.size(); ++i) bricks[i] = brickOf(items[i]);
    // Vertices on the part's border are wanted at the end: the bricks outside the part stay
    // pending for the trimmer, so it keeps them.
    const PartBorder border(source.volume(), source.layout(), options.bricks);
    EdgeVertexMap* const borderOut = options.bricks.empty() ? nullptr : options.borderVertices;
    std::vector<int64_t> pending = bricks;
    if (borderOut) {
        const std::vector<int64_t> outside = border.outside();
        pending.insert(pending.end(), outside.begin(), outside.end());
    }
    SeamTrimmer trimmer(source.volume(), source.layout(), pending, options.seamTrimEntries);
    auto identity = [](uint32_t v) { return v; };
    if (options.threads <= 1) {
        BrickExtractor extractor(source.volume(), source.layout(), options.metaCellSize, options.trilinear);
        EdgeVertexMap seams;
        BrickPrefetcher prefetcher(source, size_t(options.prefetchBricks), options.prefetchReaders);
        for (int64_t id : bricks) prefetcher.push(id);
        prefetcher.close();
        for (size_t i = 0; i < items.size(); ++i) {
            prefetcher.consumed(i);
            const BrickHandle brick = acquireTimed(items[i]);
            try {
                extractItem(extractor, items[i], brick.samples(), mesh, seams);
            } catch (const std::bad_alloc&) {  // the mesh outgrew what was reserved
                throw meshAllocationError(mesh.vertexCount(), mesh.triangleCount(), AllocationFailure::Growth);
            }
            if (brickSink) handOverBrick(bricks[i]);
            trimmer.finished(bricks[i]);
            trimmer.maybeTrim(seams);
            stream(false);
            if (i % kProgressEvery == 0 || i + 1 == items.size()) report(i + 1);
        }
        if (borderOut) border.collect(seams, *borderOut, identity);
        finish();
        return extractor.counters();
    }
    // To the brick sink on several threads: chunks of a bounded number of bricks are extracted a
    // round at a time and merged: memory holds a round's surface, not all of it. (Vertices are
    // numbered as one thread would number them whatever the chunks: see mergeChunk.)
    const size_t chunkCount =
        std::max(std::min(items.size(), size_t(options.threads) * kChunksPerThread),
                 (items.size() + kStreamedChunkBricks - 1) / kStreamedChunkBricks);
    const size_t round = size_t(options.threads) * kStreamedChunksPerThread;
    std::vector<ChunkOutput> chunks(chunkCount);
    std::atomic<size_t> done{0};
    std::mutex progressMutex;
    tbb::task_arena arena(options.threads);
    KernelCounters total;
    EdgeVertexMap seams;  // the brick-face vertices of the chunks merged so far
    for (size_t first = 0; first < chunkCount; first += round) {
        const size_t last = std::min(chunkCount, first + round);
        arena.execute([&] {
            tbb::parallel_for(first, last, [&](size_t c) {
                BrickExtractor extractor(source.volume(), source.layout(), options.metaCellSize, options.trilinear);
                const size_t begin = items.size() * c / chunkCount, end = items.size() * (c + 1) / chunkCount;
                TriangleMesh& chunkMesh = chunks[c].mesh;
                chunkMesh.indices.reserve((end - begin) * perBrick * 6);
                chunkMesh.positions.reserve((end - begin) * perBrick);
                chunkMesh.normals.reserve((end - begin) * perBrick);
                for (size_t i = begin; i < end; ++i) {
                    const BrickHandle brick = acquireTimed(items[i]);
                    extractItem(extractor, items[i], brick.samples(), chunks[c].mesh, chunks[c].seams);
                    if (brickSink)
                        chunks[c].brickEnds.push_back({chunkMesh.vertexCount(), chunkMesh.indices.size()});
                    const size_t n = ++done;
                    if (n % kProgressEvery == 0) {
                        std::lock_guard lock(progressMutex);  // the callback is not thread-safe
                        report(n);
                    }
                }
                chunks[c].counters = extractor.counters();
            });
        });
        for (size_t c = first; c < last; ++c) {
            total += chunks[c].counters;
            const size_t begin = items.size() * c / chunkCount;
            mergeChunk(chunks[c], mesh, seams, [&](size_t k) { handOverBrick(bricks[begin + k]); });
            chunks[c] = ChunkOutput();  // free the chunk's memory as soon as it is merged
            for (size_t i = begin; i < items.size() * (c + 1) / chunkCount; ++i) trimmer.finished(bricks[i]);
            trimmer.maybeTrim(seams);
        }
    }
    if (borderOut) border.collect(seams, *borderOut, identity);
    finish();
    report(items.size());
    return total;
}

}  // namespace

std::vector<int64_t> octreeActiveBricks(const BrickSource& source, double iso, int64_t* nodesVisited) {
    const MinMaxTree tree(source.layout(), source.brickRanges());
    std::vector<int64_t> bricks;
    const int64_t nodes = tree.forEachActiveBrick(iso, [&](int64_t id) { bricks.push_back(id); });
    if (nodesVisited) *nodesVisited = nodes;
    std::sort(bricks.begin(), bricks.end());  // the file's order: sequential reads
    return bricks;
}

ExtractStats extractOctree(BrickSource& source, const FullExtractOptions& options,
                               TriangleMesh& mesh, const ProgressFn& progress) {
    requireFiniteIso(options.iso);
    const auto start = Clock::now();
    ExtractStats stats;
    std::vector<int64_t> bricks = octreeActiveBricks(source, options.iso, &stats.nodesVisited);
    if (!options.bricks.empty()) {
        const PartBorder part(source.volume(), source.layout(), options.bricks);
        std::erase_if(bricks, [&](int64_t id) { return !part.holds(id); });
    }
    KernelCounters counters;
    if (writesInPlace(options)) {
        std::vector<BrickItem> items;
        items.reserve(bricks.size());
        for (int64_t id : bricks) items.push_back({id, {}});
        counters = extractInPlace(items, source, options, mesh, stats, progress, 0.0);
    } else {
        counters = extractItems(bricks, source, options, mesh, stats, progress, 0.0,
                                [&](BrickExtractor& extractor, int64_t id, const void* samples, TriangleMesh& out,
                                    EdgeVertexMap& seams) { extractor.extractBrick(id, samples, options.iso, out, seams); });
    }
    stats.bricksActive = int64_t(bricks.size());
    stats.metaCellsActive = counters.metaCellsActive;
    stats.cellsActive = counters.cellsActive;
    stats.extractSeconds = secondsSince(start);
    return stats;
}

ExtractStats extractNoise(BrickSource& source, const FullExtractOptions& options,
                              TriangleMesh& mesh, const ProgressFn& progress) {
    requireFiniteIso(options.iso);
    ExtractStats stats;
    const BrickLayout& layout = source.layout();
    BrickExtractor rangeExtractor(source.volume(), layout, options.metaCellSize);
    const uint32_t perBrick = uint32_t(rangeExtractor.metaCellsPerBrick());

    // Preprocessing, independent of the isovalue: the range of every meta-cell.
    auto start = Clock::now();
    std::vector<float> mins, maxs;
    mins.reserve(size_t(layout.brickCount()) * perBrick);
    maxs.reserve(mins.capacity());
    std::vector<BrickRange> ranges;
    for (int64_t id = 0; id < layout.brickCount(); ++id) {
        const BrickHandle brick = source.acquire(id);
        rangeExtractor.metaCellRanges(id, brick.samples(), ranges);
        for (const BrickRange& r : ranges) {
            mins.push_back(r.minValue);
            maxs.push_back(r.maxValue);
        }
        if (progress && id % kProgressEvery == 0)
            progress(0.5 * double(id) / double(layout.brickCount()));
    }
    const SpanSpaceTree tree(mins, maxs);
    stats.preprocessSeconds = secondsSince(start);

    // The query, then extraction grouped by brick (ids are brick * perBrick + meta-cell).
    start = Clock::now();
    std::vector<uint32_t> active;
    tree.query(options.iso, active);
    std::sort(active.begin(), active.end());
    stats.nodesVisited = int64_t(active.size());
    std::vector<BrickWork> work;
    std::vector<uint32_t> local(active.size());
    for (size_t i = 0; i < active.size(); ++i) {
        const int64_t id = active[i] / perBrick;
        local[i] = active[i] % perBrick;
        if (work.empty() || work.back().id != id) work.push_back({id, i, i});
        work.back().end = i + 1;
    }
    if (!options.bricks.empty()) {
        const PartBorder part(source.volume(), layout, options.bricks);
        std::erase_if(work, [&](const BrickWork& w) { return !part.holds(w.id); });
    }
    // A brick's meta-cells whose range holds iso are exactly those its surface crosses: where
    // the kernel takes bricks whole, it emits them at once, as the octree's, in the same order.
    const bool whole = rangeExtractor.wholeBricks();
    auto metaCellsOf = [&](const BrickWork& w) {
        return whole ? std::span<const uint32_t>() : std::span<const uint32_t>(local.data() + w.begin, w.end - w.begin);
    };
    KernelCounters counters;
    if (writesInPlace(options)) {
        std::vector<BrickItem> items;
        items.reserve(work.size());
        for (const BrickWork& w : work) items.push_back({w.id, metaCellsOf(w)});
        counters = extractInPlace(items, source, options, mesh, stats, progress, 0.5);
    } else {
        counters = extractItems(work, source, options, mesh, stats, progress, 0.5,
                                [&](BrickExtractor& extractor, const BrickWork& w, const void* samples,
                                    TriangleMesh& out, EdgeVertexMap& seams) {
                                    if (whole)
                                        extractor.extractBrick(w.id, samples, options.iso, out, seams);
                                    else
                                        extractor.extractMetaCells(w.id, samples, options.iso, metaCellsOf(w), out, seams);
                                });
    }
    stats.bricksActive = int64_t(work.size());
    stats.metaCellsActive = counters.metaCellsActive;
    stats.cellsActive = counters.cellsActive;
    stats.extractSeconds = secondsSince(start);
    return stats;
}

}  // namespace vdiso
