// Full extraction (octree, noise) through the kernel: closed surfaces across bricks, the same
// triangles from both methods and from memory or the store, analytic areas and volumes.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <numbers>
#include <random>
#include <set>

#include <glm/geometric.hpp>

#include "cache/brick_cache.h"
#include "core/kernel/brick_extractor.h"
#include "core/camera.h"
#include "core/extract/extract_full.h"
#include "core/extract/extract_view.h"
#include "core/kernel/iso.h"
#include "core/synth/synth.h"
#include "core/view_presets.h"
#include "io/store/brick_store.h"
#include "io/store/store_writer.h"
#include "io/readers/volume_open.h"
#include "tests/extract_test_util.h"
#include "tests/test_util.h"

namespace vdiso {
namespace {

using test::MemoryBrickSource;

// A ball of density 100 inside radius 13 falling off linearly: dense inside, as in CT, so
// normals point outwards and the enclosed volume is positive.
double ballDensity(const Dims3& d, int64_t x, int64_t y, int64_t z) {
    return 100.0 * (13.0 - test::sphereDistance(d, x, y, z)) / 13.0 + 100.0;
}

TEST(ExtractOctree, BallIsClosedAcrossBricksWithAnalyticAreaAndVolume) {
    const Dims3 dims{37, 35, 33};
    for (ScalarType type : {ScalarType::F32, ScalarType::I16}) {
        MemoryBrickSource source(dims, type, 8, [&](int64_t x, int64_t y, int64_t z) {
            return ballDensity(dims, x, y, z) * (type == ScalarType::F32 ? 1.0 : 50.0);
        });
        TriangleMesh mesh;
        const double iso = (type == ScalarType::F32 ? 100.0 : 5000.0) + 0.5;
        const ExtractStats stats = extractOctree(source, {iso, 4}, mesh);
        ASSERT_GT(mesh.triangleCount(), 1000u);
        EXPECT_EQ(test::checkClosedOriented(mesh), "") << scalarTypeName(type);
        // The surface is the sphere of radius ~13 (linear interpolation error is small).
        const double r = 13.0 * (1.0 - (iso / (type == ScalarType::F32 ? 1.0 : 50.0) - 100.0) / 100.0);
        EXPECT_NEAR(surfaceArea(mesh) / (4 * std::numbers::pi * r * r), 1.0, 0.01);
        EXPECT_NEAR(test::enclosedVolume(mesh) / (4.0 / 3.0 * std::numbers::pi * r * r * r), 1.0, 0.01);
        // Normals point outwards (along minus the gradient of a dense ball).
        const glm::vec3 centre((dims[0] - 1) / 2.0f, (dims[1] - 1) / 2.0f, (dims[2] - 1) / 2.0f);
        for (size_t v = 0; v < mesh.vertexCount(); ++v)
            ASSERT_GT(glm::dot(mesh.normals[v], glm::normalize(mesh.positions[v] - centre)), 0.9f);
        // Welded: no two vertices at the same place.
        std::set<std::tuple<float, float, float>> unique;
        for (const glm::vec3& p : mesh.positions) unique.insert({p.x, p.y, p.z});
        EXPECT_EQ(unique.size(), mesh.vertexCount());
        // Only bricks whose range holds the isovalue were read.
        int64_t activeBricks = 0;
        for (const BrickRange& b : source.brickRanges())
            activeBricks += (b.minValue <= iso && iso < b.maxValue);
        EXPECT_EQ(source.acquired(), activeBricks);
        EXPECT_EQ(stats.bricksActive, activeBricks);
        EXPECT_EQ(source.pinned(), 0);
    }
}

TEST(ExtractOctree, NoiseGivesTheSameTriangles) {
    SynthParams p;
    p.kind = SynthKind::Head;
    p.dims = {48, 44, 40};
    auto head = test::synthBrickSource(p, 8);
    MemoryBrickSource& source = *head;
    for (double iso : {kHeadSkinIso, kHeadBoneIso}) {
        for (int metaCell : {2, 4, 8}) {
            TriangleMesh octree, noise;
            extractOctree(source, {iso, metaCell}, octree);
            const ExtractStats ns = extractNoise(source, {iso, metaCell}, noise);
            ASSERT_GT(octree.triangleCount(), 100u);
            EXPECT_EQ(octree.triangleCount(), noise.triangleCount()) << iso << " M=" << metaCell;
            EXPECT_EQ(octree.vertexCount(), noise.vertexCount());
            EXPECT_EQ(test::canonicalTriangles(octree), test::canonicalTriangles(noise));
            EXPECT_EQ(test::checkClosedOriented(octree, &source.volume()), "") << iso;
            EXPECT_GT(ns.metaCellsActive, 0);
        }
    }
}

TEST(ExtractOctree, StoreThroughTheCacheEqualsMemory) {
    SynthParams p;
    p.kind = SynthKind::Turbulence;
    p.dims = {40, 36, 30};
    auto turbulence = test::synthBrickSource(p, 16);
    MemoryBrickSource& memory = *turbulence;
    test::ScratchDir dir;
    auto again = openSynthVolume(p);
    StoreWriteOptions o;
    o.brickSize = 16;
    writeBrickStore(*again, dir.file("t.vdiso"), o);
    const BrickStoreReader store(dir.file("t.vdiso"));
    // A budget of two bricks: the extraction must work inside it.
    BrickCache cache(store, 2 * store.brickBytes());
    const double iso = turbulenceIso(ScalarType::U16);
    TriangleMesh fromMemory, fromStore;
    extractOctree(memory, {iso, 4}, fromMemory);
    extractOctree(cache, {iso, 4}, fromStore);
    EXPECT_EQ(fromMemory.positions, fromStore.positions);
    EXPECT_EQ(fromMemory.indices, fromStore.indices);
    EXPECT_EQ(test::checkClosedOriented(fromStore, &cache.volume()), "");
    EXPECT_LE(cache.residentBytes(), cache.budgetBytes());
    EXPECT_GT(cache.counters().misses, 0u);
}

TEST(ExtractOctree, EmptyWhenNoBrickHoldsTheIsovalue) {
    const Dims3 dims{20, 20, 20};
    MemoryBrickSource source(dims, ScalarType::U8, 8, [](int64_t, int64_t, int64_t) { return 7.0; });
    TriangleMesh mesh;
    extractOctree(source, {7.0, 4}, mesh);  // all samples equal: nothing is above, nothing below
    EXPECT_EQ(mesh.triangleCount(), 0u);
    EXPECT_EQ(source.acquired(), 0);
}


TEST(ExtractThreads, ParallelChunksGiveTheSameWeldedSurface) {
    SynthParams p;
    p.kind = SynthKind::Turbulence;
    p.dims = {45, 41, 37};
    auto turbulence = test::synthBrickSource(p, 8);
    test::MemoryBrickSource& source = *turbulence;
    const double iso = turbulenceIso(ScalarType::U16);
    TriangleMesh serial;
    extractOctree(source, {iso, 4, 1}, serial);
    for (int threads : {2, 3}) {
        for (bool noise : {false, true}) {
            TriangleMesh parallel;
            const FullExtractOptions o{iso, 4, threads};
            if (noise)
                extractNoise(source, o, parallel);
            else
                extractOctree(source, o, parallel);
            EXPECT_EQ(parallel.vertexCount(), serial.vertexCount()) << threads << noise;
            EXPECT_EQ(test::canonicalTriangles(parallel), test::canonicalTriangles(serial));
            EXPECT_EQ(test::checkClosedOriented(parallel, &source.volume()), "");
        }
    }
    EXPECT_EQ(source.pinned(), 0);
}

// What each process of a shared extraction does (mpi/): parts of the active bricks, each
// numbering its own vertices and listing those on edges a brick outside it shares. The parts'
// triangles together are the whole surface's, and a vertex two parts make is the same point in
// both, so welding by edge key (or writing triangles alone, as STL does) gives the whole mesh.
TEST(ExtractParts, PartsMakeTheWholeSurfaceAndAgreeOnTheirBorders) {
    SynthParams p;
    p.kind = SynthKind::Turbulence;
    p.dims = {48, 48, 48};
    auto source = test::synthBrickSource(p, 8);
    const double iso = turbulenceIso(ScalarType::U16);
    TriangleMesh whole;
    extractOctree(*source, {iso, 4}, whole);
    const std::vector<int64_t> active = octreeActiveBricks(*source, iso);
    ASSERT_GT(active.size(), 30u);
    const size_t cuts[4] = {0, active.size() / 3, 2 * active.size() / 3, active.size()};
    std::vector<std::array<float, 9>> together;
    std::vector<TriangleMesh> parts(3);
    std::vector<EdgeVertexMap> borders(3);
    size_t vertices = 0, bordered = 0;
    for (int k = 0; k < 3; ++k) {
        FullExtractOptions o{iso, 4};
        o.bricks = std::span<const int64_t>(active).subspan(cuts[k], cuts[k + 1] - cuts[k]);
        o.borderVertices = &borders[size_t(k)];
        extractOctree(*source, o, parts[size_t(k)]);
        EXPECT_GT(parts[size_t(k)].triangleCount(), 0u);
        EXPECT_GT(borders[size_t(k)].size(), 0u) << "part " << k << " meets another";
        const auto t = test::canonicalTriangles(parts[size_t(k)]);
        together.insert(together.end(), t.begin(), t.end());
        vertices += parts[size_t(k)].vertexCount();
        bordered += borders[size_t(k)].size();
    }
    auto expected = test::canonicalTriangles(whole);
    std::sort(expected.begin(), expected.end());
    std::sort(together.begin(), together.end());
    EXPECT_TRUE(expected == together);
    // Every border vertex is made by another part too, at the same point, bit for bit; welding
    // them leaves the whole mesh's vertex count.
    size_t shared = 0;
    for (int k = 0; k < 3; ++k)
        borders[size_t(k)].forEach([&](uint64_t key, uint32_t v) {
            bool elsewhere = false, earlier = false;
            for (int other = 0; other < 3; ++other) {
                if (other == k) continue;
                const uint32_t w = borders[size_t(other)].find(key);
                if (w == UINT32_MAX) continue;
                elsewhere = true;
                EXPECT_EQ(parts[size_t(k)].positions[v], parts[size_t(other)].positions[w]) << "edge " << key;
                earlier = earlier || other < k;
            }
            EXPECT_TRUE(elsewhere) << "edge " << key << " of part " << k;
            shared += earlier;  // a vertex counted once, by the first part making it
        });
    EXPECT_GT(bordered, 0u);
    EXPECT_EQ(vertices - shared, whole.vertexCount());
}

// Edge slots are told apart by vertex number, which restarts with a new mesh: an extractor
// used on one mesh and then another must make the second as a fresh extractor does.
TEST(BrickExtractor, ReusedOnAnotherMeshMakesTheSameSurface) {
    SynthParams p;
    p.kind = SynthKind::Head;
    p.dims = {40, 40, 40};
    auto source = test::synthBrickSource(p, 16);
    const BrickLayout& layout = source->layout();
    BrickExtractor reused(source->volume(), layout, 4);
    TriangleMesh first;
    EdgeVertexMap firstSeams;
    for (int64_t id = 0; id < layout.brickCount(); ++id)
        reused.extractBrick(id, source->acquire(id).samples(), kHeadSkinIso, first, firstSeams);
    ASSERT_GT(first.triangleCount(), 0u);
    for (int64_t id = 0; id < layout.brickCount(); ++id) {
        TriangleMesh again, fresh;
        EdgeVertexMap seamsAgain, seamsFresh;
        const BrickHandle brick = source->acquire(id);
        reused.extractBrick(id, brick.samples(), kHeadSkinIso, again, seamsAgain);
        BrickExtractor(source->volume(), layout, 4).extractBrick(id, brick.samples(), kHeadSkinIso,
                                                                 fresh, seamsFresh);
        EXPECT_EQ(again.indices, fresh.indices) << "brick " << id;
        EXPECT_EQ(again.positions, fresh.positions) << "brick " << id;
    }
}

// Meta-cell ranges against the min and max of each meta-cell's corner samples, for every
// sample type, partial bricks and meta-cell sizes that do and do not divide the brick.
TEST(BrickExtractor, MetaCellRangesAreEachMetaCellsCornerRange) {
    std::mt19937 rng(11);
    for (ScalarType type : {ScalarType::U8, ScalarType::I16, ScalarType::U16, ScalarType::F32}) {
        test::MemoryBrickSource source({23, 17, 30}, type, 8, [&](int64_t, int64_t, int64_t) {
            return double(std::uniform_int_distribution<int>(0, 250)(rng));
        });
        const BrickLayout& layout = source.layout();
        for (int M : {1, 3, 4, 5, 8}) {
            BrickExtractor extractor(source.volume(), layout, M);
            const int n = (layout.brickSize + M - 1) / M;
            std::vector<BrickRange> ranges;
            for (int64_t id = 0; id < layout.brickCount(); ++id) {
                const BrickHandle brick = source.acquire(id);
                extractor.metaCellRanges(id, brick.samples(), ranges);
                ASSERT_EQ(ranges.size(), size_t(n) * n * n);
                const Dims3 c = layout.brickCoord(id);
                int cells[3];
                for (int a = 0; a < 3; ++a) cells[a] = layout.cellsOnAxis(a, c[a]);
                const std::vector<unsigned char>& all = source.samples();
                auto sample = [&](int64_t gx, int64_t gy, int64_t gz) {
                    const size_t i = size_t(gx + 23 * (gy + 17 * gz));
                    switch (type) {
                        case ScalarType::U8: return double(all[i]);
                        case ScalarType::I16: return double(reinterpret_cast<const int16_t*>(all.data())[i]);
                        case ScalarType::U16: return double(reinterpret_cast<const uint16_t*>(all.data())[i]);
                        case ScalarType::F32: break;
                    }
                    return double(reinterpret_cast<const float*>(all.data())[i]);
                };
                for (int mz = 0; mz < n; ++mz)
                    for (int my = 0; my < n; ++my)
                        for (int mx = 0; mx < n; ++mx) {
                            const BrickRange& r = ranges[size_t((mz * n + my) * n + mx)];
                            const int m[3] = {mx, my, mz};
                            int lo[3], hi[3];
                            bool empty = false;
                            for (int a = 0; a < 3; ++a) {
                                lo[a] = m[a] * M;
                                hi[a] = std::min(lo[a] + M, cells[a]);
                                empty = empty || lo[a] >= cells[a];
                            }
                            if (empty) {
                                EXPECT_GT(r.minValue, r.maxValue);
                                continue;
                            }
                            double vmin = INFINITY, vmax = -INFINITY;
                            for (int z = lo[2]; z <= hi[2]; ++z)
                                for (int y = lo[1]; y <= hi[1]; ++y)
                                    for (int x = lo[0]; x <= hi[0]; ++x) {
                                        const double v = sample(c[0] * 8 + x, c[1] * 8 + y, c[2] * 8 + z);
                                        vmin = std::min(vmin, v);
                                        vmax = std::max(vmax, v);
                                    }
                            ASSERT_EQ(double(r.minValue), vmin) << int(type) << " M " << M << " brick " << id;
                            ASSERT_EQ(double(r.maxValue), vmax) << int(type) << " M " << M << " brick " << id;
                        }
            }
        }
    }
}

// The map of brick-face vertices, trimmed as often as possible (every few entries) or never,
// gives the same welded surface: no face a pending brick shares is forgotten, on any path.
TEST(ExtractThreads, TrimmingTheSeamMapKeepsEveryWeld) {
    SynthParams p;
    p.kind = SynthKind::Turbulence;
    p.dims = {45, 41, 37};  // partial bricks on every axis
    auto turbulence = test::synthBrickSource(p, 8);
    const double iso = turbulenceIso(ScalarType::U16);
    FullExtractOptions never{iso, 4, 1};
    never.seamTrimEntries = SIZE_MAX;
    TriangleMesh reference;
    extractOctree(*turbulence, never, reference);
    ASSERT_GT(reference.triangleCount(), 10000u);
    for (int threads : {1, 2}) {
        for (bool noise : {false, true}) {
            FullExtractOptions often{iso, 4, threads};
            often.seamTrimEntries = 16;
            TriangleMesh trimmed;
            if (noise)
                extractNoise(*turbulence, often, trimmed);
            else
                extractOctree(*turbulence, often, trimmed);
            EXPECT_EQ(trimmed.vertexCount(), reference.vertexCount()) << threads << noise;
            EXPECT_EQ(test::canonicalTriangles(trimmed), test::canonicalTriangles(reference));
            EXPECT_EQ(test::checkClosedOriented(trimmed, &turbulence->volume()), "");
        }
    }
}


// Collects streamed pieces back into one mesh, checking they arrive in vertex order.
struct CollectingSink final : MeshSink {
    TriangleMesh all;
    int pieces = 0;
    void append(const TriangleMesh& part) override {
        EXPECT_EQ(part.firstVertex, all.positions.size());
        all.positions.insert(all.positions.end(), part.positions.begin(), part.positions.end());
        all.normals.insert(all.normals.end(), part.normals.begin(), part.normals.end());
        all.indices.insert(all.indices.end(), part.indices.begin(), part.indices.end());
        ++pieces;
    }
};

TEST(ExtractStreaming, StreamedPiecesRebuildTheHeldMesh) {
    SynthParams p;
    p.kind = SynthKind::Turbulence;
    p.dims = {80, 70, 60};
    auto source = test::synthBrickSource(p, 16);
    const double iso = turbulenceIso(ScalarType::U16);
    for (int threads : {1, 2}) {
        TriangleMesh held, streamedRest;
        const ExtractStats heldStats = extractOctree(*source, {iso, 4, threads}, held);
        CollectingSink sink;
        FullExtractOptions o{iso, 4, threads};
        o.sink = &sink;
        o.streamPieceVertices = 5000;
        const ExtractStats s = extractOctree(*source, o, streamedRest);
        EXPECT_GT(sink.pieces, 5) << "not streamed in pieces";
        EXPECT_EQ(streamedRest.vertexCount(), 0u);
        EXPECT_EQ(s.triangles, heldStats.triangles);
        EXPECT_EQ(s.vertices, held.vertexCount());
        EXPECT_EQ(sink.all.positions, held.positions) << threads;
        EXPECT_EQ(sink.all.indices, held.indices) << threads;
    }
}


// The bricks read (cache misses) are at least `atLeast`, and each of the `needed` read once,
// except that a prefetch thread descheduled for many bricks' time can come back to fetch one
// the extraction has just used and evicted: rare (1 extra read in 40 runs of 40 concurrent
// copies), bounded here at 5%. Prefetching behind the extraction read 1.9x the bricks; this
// catches it.
void expectEachReadOnce(const BrickCache& cache, double atLeast, double needed,
                        const std::string& label) {
    EXPECT_GE(double(cache.counters().misses), atLeast) << label;
    EXPECT_LE(double(cache.counters().misses), 1.05 * needed) << label;
}

// A generated head of `dims` samples written to a store of 8-cell bricks in `dir`.
std::string headStore(const test::ScratchDir& dir, const Dims3& dims) {
    SynthParams p;
    p.kind = SynthKind::Head;
    p.dims = dims;
    StoreWriteOptions o;
    o.brickSize = 8;
    writeBrickStore(*openSynthVolume(p), dir.file("h.vdiso"), o);
    return dir.file("h.vdiso");
}

TEST(ExtractPrefetch, ReadsEachListedBrickOnceAndNothingElse) {
    test::ScratchDir dir;
    const BrickStoreReader store(headStore(dir, {70, 66, 60}));
    size_t activeBricks = 0;  // of level 0
    for (int64_t id = 0; id < store.layout().brickCount(); ++id)
        activeBricks += rangeHoldsIso(store.index()[size_t(id)].minValue, store.index()[size_t(id)].maxValue,
                                      kHeadSkinIso);
    TriangleMesh without, with;
    {
        BrickCache cache(store, 16 * store.brickBytes());
        extractOctree(cache, {kHeadSkinIso, 4}, without);
    }
    for (int readers : {1, 3}) {
        with = TriangleMesh{};
        BrickCache cache(store, 16 * store.brickBytes());  // small: lookahead 8 must not thrash it
        FullExtractOptions withPrefetch{kHeadSkinIso, 4};
        withPrefetch.prefetchBricks = 8;
        withPrefetch.prefetchReaders = readers;
        extractOctree(cache, withPrefetch, with);
        EXPECT_EQ(with.positions, without.positions) << readers;
        EXPECT_EQ(with.indices, without.indices) << readers;
        // Each listed brick is read once and no other.
        expectEachReadOnce(cache, double(activeBricks), double(activeBricks),
                           "readers " + std::to_string(readers));
    }
}

// SAGE's look-ahead prefetch: the same surface, and every brick read was one the look-ahead
// found visible: the traversal's own bricks, plus those hidden by the time it got there,
// which it counts.
TEST(ExtractPrefetch, ViewDependentLookAheadReadsOnlyBricksThatPassedTheTests) {
    test::ScratchDir dir;
    const BrickStoreReader store(headStore(dir, {96, 96, 96}));
    const VolumeInfo& v = store.volume();
    for (ViewPreset preset : {ViewPreset::Distant, ViewPreset::Normal, ViewPreset::Closeup}) {
        const Camera camera = presetCamera(preset, v.origin, v.worldMax(), 400, 400);
        TriangleMesh without, with;
        PointSet pointsWithout, pointsWith;
        ExtractStats plain, ahead;
        {
            BrickCache cache(store, 64 * store.brickBytes());
            plain = extractViewDependent(cache, camera, ViewExtractOptions::sage(kHeadSkinIso),
                                         without, pointsWithout);
        }
        for (int readers : {1, 3}) {
            with = TriangleMesh{};
            pointsWith = PointSet{};
            BrickCache cache(store, 64 * store.brickBytes());
            ViewExtractOptions options = ViewExtractOptions::sage(kHeadSkinIso);
            options.prefetchBricks = 16;
            options.prefetchReaders = readers;
            ahead = extractViewDependent(cache, camera, options, with, pointsWith);
            const std::string label = std::string(viewPresetName(preset)) + ", readers " + std::to_string(readers);
            EXPECT_EQ(with.positions, without.positions) << label;
            EXPECT_EQ(with.indices, without.indices) << label;
            EXPECT_EQ(pointsWith.positions, pointsWithout.positions) << label;
            EXPECT_EQ(ahead.bricksActive, plain.bricksActive) << label;
            // Read: the traversal's bricks and the ones found ahead then hidden, each once.
            const double expected = double(ahead.bricksActive + ahead.view.bricksPrefetchedUnused);
            expectEachReadOnce(cache, expected, expected, label);
            // Hidden after being found: bounded by the look-ahead's reach each time the picture
            // grows, and here, bricks of 8 cells and a near camera, never more than were used.
            EXPECT_LE(ahead.view.bricksPrefetchedUnused, ahead.bricksActive) << label;
        }
    }
}

// Image strips on threads share one cache: each brick is read once, and the strips together
// need no brick the whole traversal did not (a strip's coverage within its columns grows as
// the whole's does).
TEST(ExtractView, StripsOnThreadsReadEachBrickOnce) {
    test::ScratchDir dir;
    const BrickStoreReader store(headStore(dir, {96, 96, 96}));
    const VolumeInfo& v = store.volume();
    for (ViewPreset preset : {ViewPreset::Distant, ViewPreset::Normal, ViewPreset::Closeup}) {
        const Camera camera = presetCamera(preset, v.origin, v.worldMax(), 400, 400);
        ExtractStats whole, strips;
        TriangleMesh wholeMesh, stripsMesh;
        PointSet points;
        {
            BrickCache cache(store, 256 * store.brickBytes());
            whole = extractViewDependent(cache, camera, ViewExtractOptions::sage(kHeadSkinIso),
                                         wholeMesh, points);
        }
        BrickCache cache(store, 256 * store.brickBytes());
        ViewExtractOptions options = ViewExtractOptions::sage(kHeadSkinIso);
        options.threads = 2;
        options.prefetchBricks = 32;
        strips = extractViewDependent(cache, camera, options, stripsMesh, points);
        const char* label = viewPresetName(preset);
        EXPECT_LE(strips.bricksActive, whole.bricksActive) << label;
        EXPECT_GE(double(strips.bricksActive), 0.9 * double(whole.bricksActive)) << label;
        // A brick one strip found ahead and another used is one read: at least those used.
        expectEachReadOnce(cache, double(strips.bricksActive),
                           double(strips.bricksActive + strips.view.bricksPrefetchedUnused), label);
        // Cells kept by both strips at their border: a small share.
        EXPECT_LE(double(stripsMesh.triangleCount()), 1.05 * double(wholeMesh.triangleCount())) << label;
    }
}

// Normals are made only for the vertices of kept cells, some of them in a later brick than
// the vertex (welded across a brick face): each must be the full extraction's normal there.
TEST(ExtractView, VertexNormalsAreTheFullExtractionsNormals) {
    test::ScratchDir dir;
    const BrickStoreReader store(headStore(dir, {96, 96, 96}));
    BrickCache cache(store, 64 * store.brickBytes());
    TriangleMesh full;
    extractOctree(cache, {kHeadSkinIso, 4}, full);
    std::map<std::array<float, 3>, glm::vec3> normalAt;
    for (size_t k = 0; k < full.positions.size(); ++k) {
        const glm::vec3& p = full.positions[k];
        normalAt[{p.x, p.y, p.z}] = full.normals[k];
    }
    const VolumeInfo& v = store.volume();
    for (ViewPreset preset : {ViewPreset::Distant, ViewPreset::Normal, ViewPreset::Closeup}) {
        const Camera camera = presetCamera(preset, v.origin, v.worldMax(), 400, 400);
        TriangleMesh view;
        PointSet points;
        extractViewDependent(cache, camera, ViewExtractOptions::sage(kHeadSkinIso), view, points);
        ASSERT_GT(view.positions.size(), 0u);
        size_t wrong = 0;
        for (size_t k = 0; k < view.positions.size(); ++k) {
            const glm::vec3& p = view.positions[k];
            const auto found = normalAt.find({p.x, p.y, p.z});
            wrong += found == normalAt.end() || found->second != view.normals[k];
        }
        EXPECT_EQ(wrong, 0u) << viewPresetName(preset) << " of " << view.positions.size();
    }
}

// A vertex is made only for a cell that keeps its triangles (polygons are tested on points
// placed from the meta-cell's projected corners before any vertex exists): every vertex of a
// view, whole or on two strips, belongs to a triangle, with no pass to drop the rest.
TEST(ExtractView, EveryVertexBelongsToATriangle) {
    test::ScratchDir dir;
    const BrickStoreReader store(headStore(dir, {96, 96, 96}));
    BrickCache cache(store, 64 * store.brickBytes());
    const VolumeInfo& v = store.volume();
    for (ViewPreset preset : {ViewPreset::Distant, ViewPreset::Normal, ViewPreset::Closeup})
        for (int threads : {1, 2}) {
            const Camera camera = presetCamera(preset, v.origin, v.worldMax(), 400, 400);
            ViewExtractOptions options = ViewExtractOptions::sage(kHeadSkinIso);
            options.threads = threads;
            TriangleMesh view;
            PointSet points;
            const ExtractStats stats = extractViewDependent(cache, camera, options, view, points);
            ASSERT_GT(view.triangleCount(), 0u);
            EXPECT_GT(stats.view.polygonsHidden, 0);  // hidden polygons were tested, and left no vertex
            std::vector<bool> used(view.positions.size(), false);
            for (const uint32_t k : view.indices) used[k - view.firstVertex] = true;
            EXPECT_EQ(std::count(used.begin(), used.end(), false), 0) << viewPresetName(preset) << ", " << threads;
        }
}

// A brick whose surface the consumer holds (ViewStream::Use::Held) marks the coverage its kept
// cells would, and makes no triangle: the bricks after it keep exactly what they keep when
// every brick's visible part is made.
TEST(ExtractView, HeldBricksMarkTheCoverageWithoutTriangles) {
    test::ScratchDir dir;
    const BrickStoreReader store(headStore(dir, {96, 96, 96}));
    BrickCache cache(store, 64 * store.brickBytes());
    struct ByBrick final : ViewStream {
        bool holdEven = false;
        std::map<int64_t, std::vector<std::array<float, 9>>> made;  // Part bricks' triangles
        size_t heldBricks = 0, heldTriangles = 0, heldVertices = 0;
        bool beginBrick(int64_t brick, int, double, Use& use) override {
            use = holdEven && brick % 2 == 0 ? Use::Held : Use::Part;
            return true;
        }
        void endBrick(int64_t brick, Use use, const TriangleMesh& mesh, const PointSet&, const TriangleMesh&) override {
            if (use == Use::Held) {
                ++heldBricks;
                heldTriangles += mesh.triangleCount();
                heldVertices += mesh.vertexCount();
                return;
            }
            std::vector<std::array<float, 9>>& out = made[brick];
            for (size_t t = 0; t < mesh.indices.size(); t += 3) {
                std::array<float, 9> triangle;
                for (int k = 0; k < 3; ++k) {
                    const glm::vec3& p = mesh.positions[mesh.indices[t + size_t(k)] - mesh.firstVertex];
                    triangle[size_t(3 * k)] = p.x;
                    triangle[size_t(3 * k + 1)] = p.y;
                    triangle[size_t(3 * k + 2)] = p.z;
                }
                out.push_back(triangle);
            }
        }
    };
    const VolumeInfo& v = store.volume();
    for (ViewPreset preset : {ViewPreset::Normal, ViewPreset::Closeup}) {
        const Camera camera = presetCamera(preset, v.origin, v.worldMax(), 400, 400);
        ByBrick all, someHeld;
        someHeld.holdEven = true;
        for (ByBrick* stream : {&all, &someHeld}) {
            ViewExtractOptions options = ViewExtractOptions::sage(kHeadSkinIso);
            options.stream = stream;
            TriangleMesh mesh;
            PointSet points;
            extractViewDependent(cache, camera, options, mesh, points);
        }
        const char* label = viewPresetName(preset);
        EXPECT_GT(someHeld.heldBricks, 0u) << label;
        EXPECT_EQ(someHeld.heldTriangles, 0u) << label;
        EXPECT_EQ(someHeld.heldVertices, 0u) << label;
        size_t compared = 0;
        for (const auto& [brick, triangles] : someHeld.made) {
            ASSERT_TRUE(all.made.contains(brick)) << label << " brick " << brick;
            EXPECT_EQ(triangles, all.made.at(brick)) << label << " brick " << brick;
            compared += triangles.size();
        }
        EXPECT_GT(compared, 0u) << label;
    }
}

}  // namespace
}  // namespace vdiso
