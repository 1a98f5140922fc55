#include "core/extract/extract_in_place.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <mutex>
#include <stdexcept>
#include <string>
#include <vector>

#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include "core/clock.h"
#include "core/extract/part_border.h"
#include "core/kernel/edge_vertex_map.h"
#include "core/kernel/placed_mesh.h"

namespace vdiso {

namespace {

constexpr int64_t kProgressEvery = 32;
// Chunks per thread: enough to balance what the triangle counts do not foresee.
constexpr size_t kChunksPerThread = 8;

struct Chunk {
    size_t begin = 0, end = 0;           // items
    size_t vertexBase = 0, indexBase = 0;  // into the arrays, from where this round starts
    uint64_t vertices = 0, triangles = 0;
    PlacedMesh placed;
    EdgeVertexMap seams;  // the vertices of brick faces this chunk made, global numbers
    // Placeholders whose owner did not make the vertex: the index to set, and the placeholder.
    std::vector<std::pair<size_t, const PlacedMesh::Placeholder*>> unmade;
};

// The items first .. first + counts.size() - 1 cut into at most `most` chunks of about equal
// triangles, with their vertex and triangle counts and their offsets from the first.
std::vector<Chunk> cutChunks(const std::vector<BrickCount>& counts, size_t first, size_t most) {
    const size_t size = counts.size();
    std::vector<uint64_t> trianglesBefore(size + 1, 0);
    for (size_t k = 0; k < size; ++k) trianglesBefore[k + 1] = trianglesBefore[k] + counts[k].triangles;
    std::vector<Chunk> chunks(std::min(size, most));
    uint64_t vertices = 0, triangles = 0;
    for (size_t c = 0; c < chunks.size(); ++c) {
        Chunk& chunk = chunks[c];
        const size_t begin = c == 0 ? 0 : chunks[c - 1].end - first;
        const uint64_t target = trianglesBefore[size] * (c + 1) / chunks.size();
        const size_t end = c + 1 == chunks.size()
                               ? size
                               : std::max(begin, size_t(std::lower_bound(trianglesBefore.begin() + std::ptrdiff_t(begin),
                                                                         trianglesBefore.end(), target) -
                                                        trianglesBefore.begin()));
        chunk.begin = first + begin;
        chunk.end = first + end;
        chunk.vertexBase = vertices;
        chunk.indexBase = 3 * triangles;
        for (size_t k = begin; k < end; ++k) {
            chunk.vertices += counts[k].vertices;
            chunk.triangles += counts[k].triangles;
        }
        vertices += chunk.vertices;
        triangles += chunk.triangles;
    }
    return chunks;
}

std::string megabytes(double bytes) { return std::to_string(int64_t(bytes / 1e6 + 0.5)) + " MB"; }

// Reserves room for `vertices` and `triangles` more (pages never written cost nothing). Only a
// hint: where the address space will not have it, the arrays grow as they are written.
void reserve(TriangleMesh& mesh, uint64_t vertices, uint64_t triangles) {
    try {
        mesh.positions.reserve(mesh.positions.size() + vertices);
        mesh.normals.reserve(mesh.normals.size() + vertices);
        mesh.indices.reserve(mesh.indices.size() + 3 * triangles);
    } catch (const std::bad_alloc&) {
    }
}

// Grows the arrays of `mesh` by `vertices` and `triangles` (to exactly that from empty; past
// what is reserved, by std::vector's doubling), or throws MeshAllocationError naming the sizes
// with the mesh as it was.
void grow(TriangleMesh& mesh, uint64_t vertices, uint64_t triangles) {
    const uint64_t limit = PlacedMesh::kPlaceholderTop / 2;  // numbers above: placeholders
    if (uint64_t(mesh.nextVertex()) + vertices > limit)
        throw MeshAllocationError("the surface has " + std::to_string(vertices) + " vertices; a mesh holds at most " +
                                  std::to_string(limit) + " (32-bit indices)");
    const size_t oldVertices = mesh.positions.size(), oldIndices = mesh.indices.size();
    try {
        mesh.positions.resize(oldVertices + vertices);
        mesh.normals.resize(oldVertices + vertices);
        mesh.indices.resize(oldIndices + 3 * triangles);
    } catch (const std::bad_alloc&) {
        mesh.positions.resize(oldVertices);
        mesh.normals.resize(oldVertices);
        mesh.indices.resize(oldIndices);
        throw meshAllocationError(vertices, triangles);
    }
}

}  // namespace

MeshAllocationError meshAllocationError(uint64_t vertices, uint64_t triangles, AllocationFailure what) {
    const double bytes = double(vertices) * 2 * sizeof(glm::vec3) + double(triangles) * 3 * sizeof(uint32_t);
    const std::string size = std::to_string(triangles) + " triangles and " + std::to_string(vertices) + " vertices";
    switch (what) {
        case AllocationFailure::Growth:
            return MeshAllocationError("cannot allocate the surface: it holds " + size + " (" + megabytes(bytes) +
                                       ") and cannot grow");
        case AllocationFailure::Working:
            return MeshAllocationError("cannot allocate the surface: " + size + " (" + megabytes(bytes) +
                                       ") were allocated, the extraction's working memory was not");
        case AllocationFailure::Output: break;
    }
    return MeshAllocationError("cannot allocate the surface: " + size + " need " + megabytes(bytes));
}

KernelCounters extractInPlace(std::span<const BrickItem> items, BrickSource& source,
                              const FullExtractOptions& options, TriangleMesh& mesh,
                              ExtractStats& stats, const ProgressFn& progress, double progressStart) {
    const VolumeInfo& volume = source.volume();
    const BrickLayout& layout = source.layout();
    const size_t n = items.size();
    const int threads = std::max(1, options.threads);
    std::vector<int64_t> bricks(n);
    for (size_t i = 0; i < n; ++i) bricks[i] = items[i].id;
    const EdgeOwnership ownership(volume.dims, layout, bricks, options.bricks.empty());
    tbb::enumerable_thread_specific<BrickExtractor> extractors(
        [&] { return BrickExtractor(volume, layout, options.metaCellSize, options.trilinear); });
    std::atomic<int64_t> waitNanoseconds{0};
    auto acquireTimed = [&](int64_t id) {
        const auto start = Clock::now();
        BrickHandle brick = source.acquire(id);
        waitNanoseconds += std::chrono::duration_cast<std::chrono::nanoseconds>(Clock::now() - start).count();
        return brick;
    };
    // Progress: the count is the first half, the emission the second.
    std::atomic<size_t> done{0};
    std::mutex progressMutex;
    auto step = [&] {
        const size_t k = ++done;
        if (!progress || (k % kProgressEvery != 0 && k != 2 * n)) return;
        std::lock_guard lock(progressMutex);  // the callback is not thread-safe
        progress(progressStart + (1.0 - progressStart) * double(k) / double(2 * n));
    };
    tbb::task_arena arena(threads);
    auto forEach = [&](size_t count, auto&& body) {
        arena.execute([&] { tbb::parallel_for(size_t(0), count, [&](size_t i) { body(i); }); });
    };

    // Rounds of at most as many bricks as half the source's cache holds, each counted, then
    // written: the emission finds the bricks the count read still in memory. Held, one round
    // and arrays of the exact size, unless the surface's bricks outgrow the cache; then the
    // arrays are reserved for the surface the first round foretells, and grow only past that.
    // Streamed, rounds of about options.streamPieceVertices vertices, each handed to the sink
    // and dropped: the next round writes into the same memory.
    const int64_t cacheRound = std::max<int64_t>(source.brickCapacity() / 2, 1);
    const int64_t fewestBricks = int64_t(threads) * int64_t(kChunksPerThread);
    const uint64_t brickArea = uint64_t(layout.brickSize) * uint64_t(layout.brickSize);
    auto roundFor = [&](uint64_t verticesPerBrick) {  // bricks of the next round
        if (!options.sink) return cacheRound;
        const uint64_t bricksForPiece = options.streamPieceVertices / std::max<uint64_t>(verticesPerBrick, 1);
        return std::min(cacheRound, std::max(fewestBricks, int64_t(std::min<uint64_t>(bricksForPiece, INT64_MAX / 2))));
    };
    size_t roundBricks = size_t(roundFor(brickArea));  // a surface crosses a brick about once
    const PartBorder border(volume, layout, options.bricks);
    EdgeVertexMap* const borderOut = options.bricks.empty() ? nullptr : options.borderVertices;
    const std::vector<int64_t> outside = borderOut ? border.outside() : std::vector<int64_t>{};
    // Brick-face vertices of earlier rounds that a brick still to come may take.
    EdgeVertexMap carried;
    std::vector<int64_t> pendingAll = bricks;
    pendingAll.insert(pendingAll.end(), outside.begin(), outside.end());
    SeamTrimmer carriedTrimmer(volume, layout, pendingAll, options.seamTrimEntries);
    const size_t vertexStart = mesh.positions.size(), indexStart = mesh.indices.size();
    uint64_t vertices = 0, triangles = 0;  // written by earlier rounds
    std::vector<BrickCount> counts;
    std::vector<std::vector<uint32_t>> activeOf;
    // An error leaves the mesh as it was (streamed, without the round that failed).
    auto restore = [&] {
        if (mesh.positions.size() < vertexStart || mesh.indices.size() < indexStart) return mesh.clear();
        mesh.positions.resize(vertexStart);
        mesh.normals.resize(vertexStart);
        mesh.indices.resize(indexStart);
    };
    try {
        for (size_t first = 0, last = 0; first < n; first = last) {
            last = std::min(n, first + roundBricks);
            // This round's vertices and triangles follow what the mesh holds.
            const uint32_t roundFirstNumber = mesh.nextVertex();
            const size_t roundVertexStart = mesh.positions.size(), roundIndexStart = mesh.indices.size();
            // 1. Count.
            // The meta-cells the emission visits, found by the count where none are listed.
            counts.assign(last - first, BrickCount{});
            activeOf.assign(last - first, {});
            forEach(last - first, [&](size_t k) {
                const BrickItem& item = items[first + k];
                const BrickHandle brick = acquireTimed(item.id);
                counts[k] = extractors.local().countInPlace(item.id, brick.samples(), options.iso, item.metaCells,
                                                            ownership, &activeOf[k]);
                step();
            });

            // 2. Chunks of about equal triangles, and their places in the arrays.
            std::vector<Chunk> chunks = cutChunks(counts, first, size_t(threads) * kChunksPerThread);
            const size_t chunkCount = chunks.size();
            uint64_t roundVertices = 0, roundTriangles = 0;
            for (const Chunk& chunk : chunks) {
                roundVertices += chunk.vertices;
                roundTriangles += chunk.triangles;
            }
            if (first == 0 && last < n && !options.sink) {
                // The surface this round foretells and a quarter more, or (the first bricks may hold
                // little of it) about 2 B^2 vertices a brick, a surface crossing it twice.
                const double scale = 1.25 * double(n) / double(last);
                const uint64_t expect = std::max(uint64_t(double(roundVertices) * scale),
                                                 uint64_t(n) * expectedVerticesPerBrick(layout.brickSize));
                reserve(mesh, expect, 2 * expect);
            }
            grow(mesh, roundVertices, roundTriangles);

            // 3. Emit, each chunk into its place. Its seam map keeps the faces a later brick
            // shares: of this chunk, of a later one (which may take a vertex this chunk owns), or
            // outside the part.
            forEach(chunkCount, [&](size_t c) {
                Chunk& chunk = chunks[c];
                PlacedMesh& placed = chunk.placed;
                placed.positions = mesh.positions.data() + roundVertexStart + chunk.vertexBase;
                placed.normals = mesh.normals.data() + roundVertexStart + chunk.vertexBase;
                placed.indices = mesh.indices.data() + roundIndexStart + chunk.indexBase;
                placed.firstVertex = roundFirstNumber + uint32_t(chunk.vertexBase);
                placed.vertexCapacity = chunk.vertices;
                placed.indexCapacity = 3 * chunk.triangles;
                placed.ownership = &ownership;
                std::vector<int64_t> pending(bricks.begin() + std::ptrdiff_t(chunk.begin), bricks.end());
                pending.insert(pending.end(), outside.begin(), outside.end());
                SeamTrimmer trimmer(volume, layout, pending, options.seamTrimEntries);
                BrickExtractor& extractor = extractors.local();
                for (size_t i = chunk.begin; i < chunk.end; ++i) {
                    const BrickHandle brick = acquireTimed(items[i].id);
                    const std::vector<uint32_t>& found = activeOf[i - first];
                    extractor.extractInPlace(items[i].id, brick.samples(), options.iso,
                                             found.empty() ? items[i].metaCells : std::span<const uint32_t>(found),
                                             placed, chunk.seams);
                    trimmer.finished(items[i].id);
                    trimmer.maybeTrim(chunk.seams);
                    step();
                }
                if (placed.vertices != chunk.vertices || placed.indexCount != 3 * chunk.triangles)
                    throw std::logic_error("full extraction: a chunk wrote fewer vertices or triangles than were counted");
            });

            // Placeholders: the owner's vertex, from its chunk or an earlier round. Where the
            // owner did not make it (bricks that disagree on a sample they share, or ranges that
            // say a brick misses the surface it crosses: a damaged or hostile store), the vertex
            // is made here, after the round's own, once per edge.
            forEach(chunkCount, [&](size_t c) {
                Chunk& chunk = chunks[c];
                for (const PlacedMesh::PlaceholderRef& ref : chunk.placed.refs) {
                    const PlacedMesh::Placeholder& p = chunk.placed.placeholders[ref.placeholder];
                    const int64_t owner = ownership.owner(p.key);
                    const size_t i = size_t(std::lower_bound(bricks.begin(), bricks.end(), owner) - bricks.begin());
                    uint32_t v = UINT32_MAX;
                    if (owner >= 0 && i < first) {
                        v = carried.find(p.key);
                    } else if (owner >= 0 && i < n) {
                        const auto ownerChunk = std::upper_bound(chunks.begin(), chunks.end(), i,
                                                                 [](size_t k, const Chunk& other) { return k < other.end; });
                        v = ownerChunk->seams.find(p.key);
                        if (ownerChunk->placed.isPlaceholder(v)) v = UINT32_MAX;
                    }
                    if (v == UINT32_MAX)
                        chunk.unmade.push_back({roundIndexStart + chunk.indexBase + ref.index, &p});
                    else
                        mesh.indices[roundIndexStart + chunk.indexBase + ref.index] = v;
                }
            });
            EdgeVertexMap made;
            for (const Chunk& chunk : chunks)
                for (const auto& [index, p] : chunk.unmade) {
                    uint32_t v = made.find(p->key);
                    if (v == UINT32_MAX) {
                        v = mesh.nextVertex();
                        mesh.addVertex(p->position, p->normal);
                        made.insert(p->key, v);
                        ++roundVertices;
                    }
                    mesh.indices[index] = v;
                }
            if (last < n)
                made.forEach([&](uint64_t key, uint32_t v) {
                    if (carried.find(key) == UINT32_MAX) carried.insert(key, v);
                });
            for (const Chunk& chunk : chunks) {
                auto real = [&](uint32_t v) { return chunk.placed.isPlaceholder(v) ? UINT32_MAX : v; };
                if (borderOut) border.collect(chunk.seams, *borderOut, real);
                if (last == n) continue;
                chunk.seams.forEach([&](uint64_t key, uint32_t v) {
                    if (real(v) != UINT32_MAX && carried.find(key) == UINT32_MAX) carried.insert(key, v);
                });
            }
            for (size_t i = first; i < last; ++i) carriedTrimmer.finished(bricks[i]);
            carriedTrimmer.maybeTrim(carried);
            vertices += roundVertices;
            triangles += roundTriangles;
            if (options.sink) {
                drainInto(*options.sink, mesh);
                roundBricks = size_t(roundFor(roundVertices / std::max<uint64_t>(last - first, 1)));
            }
        }
    } catch (const MeshAllocationError&) {
        restore();
        throw;
    } catch (const std::bad_alloc&) {
        const uint64_t held = mesh.positions.size() - std::min(vertexStart, mesh.positions.size());
        const uint64_t heldIndices = mesh.indices.size() - std::min(indexStart, mesh.indices.size());
        restore();
        throw meshAllocationError(held, heldIndices / 3, AllocationFailure::Working);
    } catch (...) {
        restore();
        throw;
    }

    KernelCounters total;
    for (const BrickExtractor& e : extractors) total += e.counters();
    stats.triangles = triangles;
    stats.vertices = vertices;
    stats.brickWaitSeconds = double(waitNanoseconds) * 1e-9;
    if (progress && n == 0) progress(1.0);
    return total;
}

}  // namespace vdiso
