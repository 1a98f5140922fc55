// A full extraction held in memory is counted, then written in place (core/extract/extract_in_place.h):
// the same mesh, bit for bit, as the streamed extraction appending brick by brick, for any
// thread count and both methods; and an output that cannot be held is refused before anything
// is written.
#include <gtest/gtest.h>

#include <random>
#include <string>

#include "core/extract/extract_full.h"
#include "core/extract/extract_in_place.h"
#include "core/kernel/brick_extractor.h"
#include "core/kernel/edge_vertex_map.h"
#include "core/kernel/iso.h"
#include "core/kernel/placed_mesh.h"
#include "core/synth/synth.h"
#include "tests/extract_test_util.h"
#include "tests/test_util.h"

namespace vdiso {
namespace {

// What a streamed extraction hands over, appended into one mesh.
struct Appended final : MeshSink {
    TriangleMesh all;
    void append(const TriangleMesh& part) override {
        all.positions.insert(all.positions.end(), part.positions.begin(), part.positions.end());
        all.normals.insert(all.normals.end(), part.normals.begin(), part.normals.end());
        all.indices.insert(all.indices.end(), part.indices.begin(), part.indices.end());
    }
};

// Generated turbulence (a surface with many pieces) in bricks of 8 cells.
std::unique_ptr<test::MemoryBrickSource> turbulence(const Dims3& dims) {
    SynthParams p;
    p.kind = SynthKind::Turbulence;
    p.dims = dims;
    return test::synthBrickSource(p, 8);
}

ExtractStats extract(bool noise, BrickSource& source, const FullExtractOptions& o, TriangleMesh& mesh) {
    return noise ? extractNoise(source, o, mesh) : extractOctree(source, o, mesh);
}

// Many chunks (8 a thread) over bricks of 8 cells, partial on every axis: chunk borders cut
// faces, edges and corners of bricks, so vertices owned in one chunk are placeholders in others.
TEST(ExtractInPlace, IsTheStreamedMeshBitForBitOnAnyThreads) {
    auto source = turbulence({45, 41, 37});
    const double iso = turbulenceIso(ScalarType::U16);
    for (bool noise : {false, true}) {
        Appended streamed;
        FullExtractOptions s{iso, 4, 1};
        s.sink = &streamed;
        TriangleMesh rest;
        extract(noise, *source, s, rest);
        ASSERT_GT(streamed.all.triangleCount(), 10000u);
        for (int threads : {1, 2, 3, 5}) {
            TriangleMesh held;
            const ExtractStats stats = extract(noise, *source, {iso, 4, threads}, held);
            EXPECT_EQ(held.positions, streamed.all.positions) << threads << noise;
            EXPECT_EQ(held.normals, streamed.all.normals) << threads << noise;
            EXPECT_EQ(held.indices, streamed.all.indices) << threads << noise;
            EXPECT_EQ(stats.triangles, held.triangleCount());
            EXPECT_EQ(stats.vertices, held.vertexCount());
            // Streamed on these threads too: rounds of about 3,000 vertices, each written in
            // place and handed over, later rounds taking vertices of earlier ones.
            Appended pieces;
            FullExtractOptions o{iso, 4, threads};
            o.sink = &pieces;
            o.streamPieceVertices = 3000;
            TriangleMesh passing;
            const ExtractStats streamedStats = extract(noise, *source, o, passing);
            EXPECT_EQ(passing.vertexCount(), 0u);
            EXPECT_EQ(streamedStats.triangles, held.triangleCount());
            EXPECT_EQ(pieces.all.positions, streamed.all.positions) << threads << noise;
            EXPECT_EQ(pieces.all.normals, streamed.all.normals) << threads << noise;
            EXPECT_EQ(pieces.all.indices, streamed.all.indices) << threads << noise;
        }
    }
    EXPECT_EQ(source->pinned(), 0);
}

// A source whose cache holds 10 bricks: the bricks are counted and written 5 at a time, each
// round growing the arrays; vertices owned by a brick of an earlier round are taken from it.
class SmallCache final : public BrickSource {
public:
    explicit SmallCache(BrickSource& inner) : mInner(inner) {}
    const VolumeInfo& volume() const override { return mInner.volume(); }
    const BrickLayout& layout() const override { return mInner.layout(); }
    std::span<const BrickRange> brickRanges() const override { return mInner.brickRanges(); }
    BrickHandle acquire(int64_t id) override { return mInner.acquire(id); }
    int64_t brickCapacity() const override { return 10; }

protected:
    void release(int64_t) override {}

private:
    BrickSource& mInner;
};

TEST(ExtractInPlace, RoundsOfWhatTheCacheHoldsGiveTheSameMesh) {
    auto source = turbulence({45, 41, 37});
    SmallCache small(*source);
    const double iso = turbulenceIso(ScalarType::U16);
    TriangleMesh whole;
    extractOctree(*source, {iso, 4, 1}, whole);
    for (bool noise : {false, true})
        for (int threads : {1, 3}) {
            TriangleMesh rounds;
            extract(noise, small, {iso, 4, threads}, rounds);
            EXPECT_EQ(rounds.positions, whole.positions) << threads << noise;
            EXPECT_EQ(rounds.normals, whole.normals) << threads << noise;
            EXPECT_EQ(rounds.indices, whole.indices) << threads << noise;
        }
    EXPECT_EQ(source->pinned(), 0);
}

// Two bricks that disagree on the face they share (a damaged store): brick 1 sees the surface
// cross edges of that face, brick 0, their owner, does not. Written in place, brick 1's
// placeholders for them find no vertex at their owner and make it themselves, once per edge:
// the triangles one thread makes, numbered otherwise.
TEST(ExtractInPlace, BricksThatDisagreeOnASharedFaceStillGiveEveryTriangle) {
    test::MemoryBrickSource source({17, 9, 9}, ScalarType::U16, 8, [](int64_t x, int64_t y, int64_t) {
        return x < 8 ? 10.0 : y < 4 ? 100.0 : 50.0;
    });
    // Brick 0's copy of the face x = 8: all above the isovalue, so no edge of it is crossed there.
    const int side = source.layout().side();
    auto* face = reinterpret_cast<uint16_t*>(source.brickSamples(0));
    for (int z = -1; z <= 9; ++z)
        for (int y = -1; y <= 9; ++y) face[BrickLayout::cornerIndex(side, 8, y, z)] = 100;
    const double iso = 75;
    TriangleMesh serial;
    extractOctree(source, {iso, 4, 1}, serial);
    for (int threads : {2, 3}) {
        TriangleMesh placed;
        extractOctree(source, {iso, 4, threads}, placed);
        ASSERT_GT(placed.triangleCount(), 0u);
        EXPECT_EQ(test::canonicalTriangles(placed), test::canonicalTriangles(serial)) << threads;
        EXPECT_EQ(placed.vertexCount(), serial.vertexCount()) << threads;
        for (uint32_t v : placed.indices) ASSERT_LT(v, placed.vertexCount());
    }
}

// Appended to a mesh that already holds a surface, numbered after it.
TEST(ExtractInPlace, AppendsAfterWhatTheMeshHolds) {
    auto source = turbulence({33, 30, 27});
    const double iso = turbulenceIso(ScalarType::U16);
    TriangleMesh once, twice;
    extractOctree(*source, {iso, 4, 2}, once);
    extractOctree(*source, {iso, 4, 2}, twice);
    extractOctree(*source, {iso, 4, 2}, twice);
    ASSERT_EQ(twice.vertexCount(), 2 * once.vertexCount());
    for (size_t i = 0; i < once.indices.size(); ++i) {
        EXPECT_EQ(twice.indices[i], once.indices[i]);
        EXPECT_EQ(twice.indices[once.indices.size() + i], once.indices[i] + uint32_t(once.vertexCount()));
    }
}

// The count is what the kernel writes, brick by brick, on every sample type and where samples
// are not finite (NaN counts as below every isovalue, infinities as ordered values): from the
// whole brick's corner rows (bricks of 8, emitted whole), or meta-cell by meta-cell (rows of
// more than 64 corners, bricks of 64 and more).
TEST(ExtractInPlace, CountsAreWhatEachBrickWrites) {
    for (const auto& [brickSize, dims] : {std::pair{8, Dims3{27, 22, 19}}, std::pair{64, Dims3{70, 20, 9}}})
    for (ScalarType type : {ScalarType::U8, ScalarType::I16, ScalarType::U16, ScalarType::F32}) {
        test::MemoryBrickSource source(dims, type, brickSize, [&](int64_t x, int64_t y, int64_t z) {
            const double v = double((x * 7 + y * 13 + z * 29) % 23);
            if (type == ScalarType::F32 && (x + y + z) % 11 == 0) return (x % 2) ? double(NAN) : double(INFINITY);
            return v;
        });
        const double iso = 11.5;
        std::vector<int64_t> bricks;
        for (int64_t id = 0; id < source.layout().brickCount(); ++id) bricks.push_back(id);
        const EdgeOwnership ownership(source.volume().dims, source.layout(), bricks, false);
        BrickExtractor counter(source.volume(), source.layout(), 4), writer(source.volume(), source.layout(), 4);
        std::vector<BrickCount> counts;
        uint64_t vertices = 0, triangles = 0;
        for (int64_t id : bricks) {
            const BrickHandle brick = source.acquire(id);
            std::vector<uint32_t> found;
            counts.push_back(counter.countInPlace(id, brick.samples(), iso, {}, ownership, &found));
            vertices += counts.back().vertices;
            triangles += counts.back().triangles;
            // The meta-cells it finds crossed are those whose range holds the isovalue (NOISE's,
            // which the emission of a whole brick takes all at once): listed meta-cell by
            // meta-cell, counted by the whole brick's emission.
            std::vector<BrickRange> ranges;
            counter.metaCellRanges(id, brick.samples(), ranges);
            std::vector<uint32_t> ranged;
            for (size_t m = 0; m < ranges.size(); ++m)
                if (rangeHoldsIso(ranges[m].minValue, ranges[m].maxValue, iso)) ranged.push_back(uint32_t(m));
            if (counter.wholeBricks()) {
                EXPECT_TRUE(found.empty());
                TriangleMesh scratch;
                EdgeVertexMap scratchSeams;
                const int64_t before = counter.counters().metaCellsActive;
                counter.extractBrick(id, brick.samples(), iso, scratch, scratchSeams);
                EXPECT_EQ(counter.counters().metaCellsActive - before, int64_t(ranged.size())) << int(type) << " brick " << id;
            } else {
                EXPECT_EQ(found, ranged) << int(type) << " brick " << id;
            }
        }
        ASSERT_GT(triangles, 1000u) << int(type) << " bricks of " << brickSize;
        // One chunk: every brick writes into one range; no placeholder may remain unset.
        MeshArray<glm::vec3> positions(vertices), normals(vertices);
        MeshArray<uint32_t> indices(3 * triangles);
        PlacedMesh placed;
        placed.positions = positions.data();
        placed.normals = normals.data();
        placed.indices = indices.data();
        placed.vertexCapacity = vertices;
        placed.indexCapacity = 3 * triangles;
        placed.ownership = &ownership;
        EdgeVertexMap seams;
        for (int64_t id : bricks) {
            const size_t v0 = placed.vertices, i0 = placed.indexCount;
            const BrickHandle brick = source.acquire(id);
            writer.extractInPlace(id, brick.samples(), iso, {}, placed, seams);
            EXPECT_EQ(placed.vertices - v0, counts[size_t(id)].vertices) << int(type) << " brick " << id;
            EXPECT_EQ(placed.indexCount - i0, 3 * counts[size_t(id)].triangles) << int(type) << " brick " << id;
        }
        EXPECT_TRUE(placed.placeholders.empty());
        TriangleMesh mesh;
        extractOctree(source, {iso, 4, 1}, mesh);
        EXPECT_EQ(mesh.indices.size(), indices.size());
    }
}

// More vertices than 32-bit indices can number: refused before anything is allocated or
// written, naming the count, and the mesh is left as it was.
TEST(ExtractInPlace, AnOutputTooLargeIsRefusedWithItsSize) {
    auto source = turbulence({33, 30, 27});
    TriangleMesh mesh;
    mesh.firstVertex = PlacedMesh::kPlaceholderTop / 2 - 100;  // as if that many were streamed
    try {
        extractOctree(*source, {turbulenceIso(ScalarType::U16), 4, 2}, mesh);
        FAIL() << "no error";
    } catch (const MeshAllocationError& e) {
        EXPECT_NE(std::string(e.what()).find("vertices; a mesh holds at most"), std::string::npos) << e.what();
    }
    EXPECT_EQ(mesh.vertexCount(), 0u);
    EXPECT_EQ(mesh.indices.size(), 0u);
    EXPECT_EQ(source->pinned(), 0);
}

// The command line, under an address-space limit below a noise volume's surface (34 M
// triangles, 817 MB): a clear error naming the size and exit code 1, on one thread (where the
// surface outgrows what was reserved) and on two (where the count knows it before writing).
TEST(ExtractInPlace, TheCommandLineNamesTheSizeOfASurfaceItCannotHold) {
    if (VDISO_UNDER_ASAN) GTEST_SKIP() << "an address-space limit and AddressSanitizer exclude each other";
    test::ScratchDir dir;
    std::string noise(size_t(200) * 200 * 200, '\0');
    std::mt19937 rng(1);
    for (char& c : noise) c = char(rng() & 255);
    test::writeFile(dir.file("noise.raw"), noise);
    ASSERT_EQ(test::runCommand(std::string(VDISO_BINARY) + " convert " + dir.file("noise.raw") + " " +
                               dir.file("noise.vdiso") + " --dims 200,200,200 --type u8 --quiet").exitCode, 0);
    for (int threads : {1, 2}) {
        const test::CommandResult r = test::runCommand(
            "ulimit -v 600000; " + std::string(VDISO_BINARY) + " extract " + dir.file("noise.vdiso") +
            " --iso 127.5 --method octree --threads " + std::to_string(threads) + " --stats - --quiet");
        EXPECT_EQ(r.exitCode, 1) << threads << r.output;
        EXPECT_NE(r.output.find("error: cannot allocate the surface: "), std::string::npos) << threads << r.output;
        EXPECT_NE(r.output.find(" MB"), std::string::npos) << r.output;
        EXPECT_EQ(r.output.find("bad_alloc"), std::string::npos) << r.output;
    }
}

}  // namespace
}  // namespace vdiso
