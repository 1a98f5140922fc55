// Post-processing out of core (core/mesh_post/mesh_slabs.h, core/mesh_post/mesh_pieces.h, io/mesh/mesh_post.h): a full
// extraction handed over brick by brick, spooled and finished slab by slab, against the same
// operations on the whole mesh held in memory.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <map>

#include <glm/geometric.hpp>

#include "core/extract/extract_full.h"
#include "core/mesh_post/mesh_pieces.h"
#include "core/mesh_post/mesh_smooth.h"
#include "io/mesh/mesh_post.h"
#include "tests/extract_test_util.h"
#include "tests/test_util.h"

using namespace vdiso;

namespace {

std::unique_ptr<test::MemoryBrickSource> turbulence(int brickSize) {
    SynthParams p;
    p.kind = SynthKind::Turbulence;
    p.dims = {80, 70, 60};
    return test::synthBrickSource(p, brickSize);
}
constexpr double kTurbulenceIso = 32767.5;

// The surface of `source` at `iso` through PostProcessedMesh, collected in memory.
TriangleMesh postProcessed(BrickSource& source, double iso, const MeshPostOptions& post, int threads,
                           MeshPostStats* stats = nullptr, bool noise = false) {
    test::ScratchDir dir;
    TriangleMesh result, rest;
    MeshAppender out(result);
    MeshPostOptions options = post;
    options.threads = threads;  // slabs shaped at once: the same result
    PostProcessedMesh mesh(dir.file("m.ply"), source.layout(), options, out);
    FullExtractOptions o{iso, 4, threads};
    o.brickSink = &mesh;
    const ExtractStats extracted = noise ? extractNoise(source, o, rest) : extractOctree(source, o, rest);
    EXPECT_EQ(rest.vertexCount() + rest.indices.size(), 0u) << "the brick sink took everything";
    const MeshPostStats s = mesh.finish();
    EXPECT_EQ(s.trianglesIn, extracted.triangles);
    EXPECT_EQ(s.trianglesOut, result.triangleCount());
    EXPECT_EQ(s.verticesOut, result.vertexCount());
    if (stats) *stats = s;
    return result;
}

TriangleMesh held(BrickSource& source, double iso, int threads, bool noise = false) {
    TriangleMesh mesh;
    FullExtractOptions o{iso, 4, threads};
    noise ? extractNoise(source, o, mesh) : extractOctree(source, o, mesh);
    return mesh;
}

template <class A>
bool sameBits(const A& a, const A& b) {
    return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(a[0])) == 0;
}

// Every vertex is used by some triangle.
bool allVerticesUsed(const TriangleMesh& mesh) {
    std::vector<bool> used(mesh.vertexCount(), false);
    for (uint32_t v : mesh.indices) used[v] = true;
    return std::all_of(used.begin(), used.end(), [](bool u) { return u; });
}

// Distance from (x,y,z) to the segment a-b.
double segmentDistance(glm::dvec3 p, glm::dvec3 a, glm::dvec3 b) {
    const glm::dvec3 ab = b - a;
    const double t = std::clamp(glm::dot(p - a, ab) / glm::dot(ab, ab), 0.0, 1.0);
    return glm::length(p - (a + t * ab));
}

struct Ball {
    glm::dvec3 centre;
    double radius;
};

// Above 0 inside any of the balls (and capsules, balls swept along a segment), f32 samples.
std::unique_ptr<test::MemoryBrickSource> blobs(const Dims3& dims, std::vector<Ball> balls,
                                               std::vector<std::pair<glm::dvec3, glm::dvec3>> capsules = {},
                                               double capsuleRadius = 0) {
    return std::make_unique<test::MemoryBrickSource>(dims, ScalarType::F32, 8, [=](int64_t x, int64_t y, int64_t z) {
        const glm::dvec3 p{double(x), double(y), double(z)};
        double f = -1e9;
        for (const Ball& b : balls) f = std::max(f, b.radius - glm::length(p - b.centre));
        for (const auto& [a, b] : capsules) f = std::max(f, capsuleRadius - segmentDistance(p, a, b));
        return f;
    });
}

}  // namespace

TEST(MeshPost, WithoutOperationsGivesTheExtractedMesh) {
    auto source = turbulence(8);
    for (bool noise : {false, true})
        for (int threads : {1, 2}) {
            const TriangleMesh expected = held(*source, kTurbulenceIso, 1, noise);  // any thread count
            MeshPostStats stats;
            const TriangleMesh got = postProcessed(*source, kTurbulenceIso, {}, threads, &stats, noise);
            EXPECT_GT(expected.triangleCount(), 10000u);
            EXPECT_TRUE(sameBits(got.positions, expected.positions)) << threads << " threads, noise " << noise;
            EXPECT_TRUE(sameBits(got.normals, expected.normals));
            EXPECT_TRUE(sameBits(got.indices, expected.indices));
            EXPECT_EQ(stats.slabs, 8);  // 59 cells in bricks of 8
            EXPECT_EQ(stats.haloSlabs, 1);
            EXPECT_GT(stats.spoolBytes, expected.vertexCount() * 24);
        }
}

// Smoothing a slab with the slabs it reaches gives, bit for bit, what smoothing the whole mesh
// gives; with a halo one slab short it would not (the test would see it: the count below).
TEST(MeshPost, SmoothingSlabBySlabEqualsSmoothingTheWholeMesh) {
    auto source = turbulence(8);
    for (int iterations : {2, 10})
        for (int threads : {1, 2}) {
            TriangleMesh expected = held(*source, kTurbulenceIso, threads);
            const MeshArray<glm::vec3> before = expected.positions;
            smoothTaubin(expected.positions, expected.indices, iterations);
            triangleNormals(expected.positions, expected.indices, expected.normals, 0,
                            uint32_t(expected.vertexCount()));
            MeshPostOptions o;
            o.smoothIterations = iterations;
            MeshPostStats stats;
            const TriangleMesh got = postProcessed(*source, kTurbulenceIso, o, threads, &stats);
            EXPECT_EQ(stats.haloSlabs, iterations == 2 ? 1 : 3);  // 21 edges reach into a third brick
            EXPECT_TRUE(sameBits(got.indices, expected.indices));
            EXPECT_TRUE(sameBits(got.positions, expected.positions)) << iterations << " iterations";
            EXPECT_TRUE(sameBits(got.normals, expected.normals));
            size_t moved = 0;
            for (size_t v = 0; v < before.size(); ++v) moved += before[v] != got.positions[v];
            EXPECT_GT(moved, before.size() * 9 / 10) << "smoothing moved the vertices";
        }
}

TEST(MeshPost, SmoothingKeepsVolumeAndTheCutOnTheVolumesFaces) {
    // A ball: Taubin smoothing keeps its volume (plain Laplacian smoothing would shrink it).
    auto ball = blobs({40, 40, 40}, {{{19.5, 19.3, 19.7}, 13.0}});
    const TriangleMesh before = held(*ball, 0.0, 1);
    MeshPostOptions o;
    o.smoothIterations = 20;
    const TriangleMesh after = postProcessed(*ball, 0.0, o, 1);
    EXPECT_EQ(test::checkClosedOriented(after), "");
    EXPECT_NEAR(test::enclosedVolume(after) / test::enclosedVolume(before), 1.0, 0.02);
    // Turbulence leaves through the volume's faces: the vertices there stay where they are.
    auto source = turbulence(8);
    const VolumeInfo& v = source->volume();
    const TriangleMesh rough = held(*source, kTurbulenceIso, 2);
    const TriangleMesh smoothed = postProcessed(*source, kTurbulenceIso, o, 2);
    EXPECT_EQ(test::checkClosedOriented(smoothed, &v), "");
    size_t onFaces = 0;
    for (size_t i = 0; i < rough.vertexCount(); ++i) {
        const glm::vec3 p = rough.positions[i];
        bool onFace = false;
        for (int a = 0; a < 3; ++a) onFace |= p[a] == 0.0f || p[a] == float(v.dims[size_t(a)] - 1);
        if (!onFace) continue;
        ++onFaces;
        EXPECT_EQ(smoothed.positions[i], p) << "vertex " << i;
    }
    EXPECT_GT(onFaces, 1000u);
}

TEST(MeshPost, DecimationKeepsAClosedSurfaceClosedAcrossSlabs) {
    // A bumpy ball over 5 slabs of bricks.
    auto source = std::make_unique<test::MemoryBrickSource>(
        Dims3{44, 44, 44}, ScalarType::F32, 8, [](int64_t x, int64_t y, int64_t z) {
            const glm::dvec3 p = glm::dvec3(double(x), double(y), double(z)) - glm::dvec3(21.6, 21.4, 21.2);
            const double r = glm::length(p);
            return 15.0 + 2.5 * std::sin(p.x * 0.5) * std::cos(p.y * 0.4) + std::sin(p.z * 0.7) - r;
        });
    const TriangleMesh full = held(*source, 0.0, 1);
    ASSERT_EQ(test::checkClosedOriented(full), "");
    for (int threads : {1, 2})
        for (int smooth : {0, 4}) {
            MeshPostOptions o;
            o.decimateRatio = 0.25;
            o.smoothIterations = smooth;
            MeshPostStats stats;
            const TriangleMesh got = postProcessed(*source, 0.0, o, threads, &stats);
            EXPECT_EQ(test::checkClosedOriented(got), "") << smooth << " smoothing, " << threads << " threads";
            EXPECT_TRUE(allVerticesUsed(got));
            const double kept = double(got.triangleCount()) / double(full.triangleCount());
            EXPECT_GT(kept, 0.2);
            EXPECT_LT(kept, 0.35) << "locked slab borders cost a few triangles, not many";
            // Decimation to a quarter loses 0.5 % of the volume unsmoothed and 3.2 % smoothed
            // (smoothing alone: 0.01 %); collapses of equal cost go in the triangles' order, and
            // the kernel's order (rows of a whole brick) moved the second from under 3 %.
            EXPECT_NEAR(test::enclosedVolume(got) / test::enclosedVolume(full), 1.0, 0.04);
            for (const glm::vec3& n : got.normals) EXPECT_NEAR(glm::length(n), 1.0f, 1e-4f);
        }
}

TEST(MeshPost, LargestAndMinPieceKeepTheRightBalls) {
    const Dims3 dims{64, 40, 40};
    const Ball small{{10.2, 20.1, 20.3}, 4.5}, large{{30.3, 19.8, 20.2}, 9.0}, middle{{51.7, 20.4, 19.6}, 6.5};
    auto three = blobs(dims, {small, large, middle});
    MeshPostOptions o;
    o.largestPiece = true;
    MeshPostStats stats;
    TriangleMesh got = postProcessed(*three, 0.0, o, 2, &stats);
    EXPECT_EQ(stats.pieces, 3u);
    EXPECT_EQ(stats.piecesKept, 1u);
    auto onlyLarge = blobs(dims, {large});
    EXPECT_EQ(test::canonicalTriangles(got), test::canonicalTriangles(held(*onlyLarge, 0.0, 1)));
    EXPECT_TRUE(allVerticesUsed(got));

    // The smallest ball has fewer triangles than the middle one: a threshold between them.
    const size_t smallTriangles = held(*blobs(dims, {small}), 0.0, 1).triangleCount();
    const size_t middleTriangles = held(*blobs(dims, {middle}), 0.0, 1).triangleCount();
    ASSERT_LT(smallTriangles, middleTriangles);
    o = {};
    o.minPieceTriangles = (smallTriangles + middleTriangles) / 2;
    got = postProcessed(*three, 0.0, o, 1, &stats);
    EXPECT_EQ(stats.piecesKept, 2u);
    EXPECT_EQ(test::canonicalTriangles(got), test::canonicalTriangles(held(*blobs(dims, {large, middle}), 0.0, 1)));
    o.minPieceTriangles = smallTriangles;  // "fewer than N" are dropped: exactly N stays
    postProcessed(*three, 0.0, o, 1, &stats);
    EXPECT_EQ(stats.piecesKept, 3u);
}

// An arch whose two legs meet only in the top slab is one piece: labels given to each leg in
// the slabs below are joined there.
TEST(MeshPost, PiecesJoinAcrossSlabs) {
    const Dims3 dims{48, 30, 48};
    const glm::dvec3 leftFoot(10, 15, 3), rightFoot(37, 15, 3), leftTop(10, 15, 40), rightTop(37, 15, 40);
    const Ball pebble{{24.0, 15.0, 10.0}, 3.2};
    auto arch = blobs(dims, {pebble}, {{leftFoot, leftTop}, {rightFoot, rightTop}, {leftTop, rightTop}}, 4.2);
    MeshPostOptions o;
    o.largestPiece = true;
    MeshPostStats stats;
    const TriangleMesh got = postProcessed(*arch, 0.0, o, 1, &stats);
    EXPECT_EQ(stats.pieces, 2u);
    auto archAlone = blobs(dims, {}, {{leftFoot, leftTop}, {rightFoot, rightTop}, {leftTop, rightTop}}, 4.2);
    EXPECT_EQ(test::canonicalTriangles(got), test::canonicalTriangles(held(*archAlone, 0.0, 1)));
    EXPECT_EQ(test::checkClosedOriented(got, &arch->volume()), "");  // the feet leave the volume
}

TEST(MeshPost, PiecesRefuseTrianglesOutsideTheirSlabs) {
    MeshPieces pieces;
    std::vector<uint32_t> labels;
    const std::vector<uint32_t> first{0, 1, 2};
    pieces.addSlab(0, 3, first, labels);
    EXPECT_EQ(labels, std::vector<uint32_t>{0});
    pieces.addSlab(3, 3, std::vector<uint32_t>{3, 4, 2}, labels);  // uses the slab before: fine
    EXPECT_THROW(pieces.addSlab(6, 3, std::vector<uint32_t>{6, 7, 1}, labels), std::invalid_argument);
    EXPECT_THROW(pieces.addSlab(7, 3, first, labels), std::invalid_argument);  // not numbered on
}
// Turbulence is thin and noisy, and cut by the volume's faces: decimated hard, it stays closed
// (every edge inside the volume has as many triangles one way as the other), though the
// simplifier pinches a few thin parts into edges of four triangles.
TEST(MeshPost, DecimationLeavesNoCrackInAThinNoisySurface) {
    SynthParams p;
    p.kind = SynthKind::Turbulence;
    p.dims = {130, 120, 110};
    auto source = test::synthBrickSource(p, 16);
    const VolumeInfo& volume = source->volume();
    MeshPostOptions o;
    o.decimateRatio = 0.1;
    o.smoothIterations = 5;
    o.minPieceTriangles = 50;
    MeshPostStats stats;
    const TriangleMesh got = postProcessed(*source, kTurbulenceIso, o, 2, &stats);
    EXPECT_LT(double(got.triangleCount()), 0.2 * double(stats.trianglesIn));
    std::map<std::pair<uint32_t, uint32_t>, int> directed;
    for (size_t t = 0; t < got.triangleCount(); ++t)
        for (int k = 0; k < 3; ++k) ++directed[{got.indices[3 * t + k], got.indices[3 * t + (k + 1) % 3]}];
    auto onOneFace = [&](uint32_t a, uint32_t b) {
        for (int axis = 0; axis < 3; ++axis)
            for (float face : {0.0f, float(volume.dims[size_t(axis)] - 1)})
                if (got.positions[a][axis] == face && got.positions[b][axis] == face) return true;
        return false;
    };
    size_t edges = 0, pinched = 0;
    for (const auto& [edge, count] : directed) {
        const auto back = directed.find({edge.second, edge.first});
        const int reverse = back == directed.end() ? 0 : back->second;
        if (edge.first < edge.second || reverse == 0) ++edges;
        if (reverse != count) {
            EXPECT_TRUE(onOneFace(edge.first, edge.second)) << edge.first << "-" << edge.second;
        }
        if (edge.first < edge.second && count + reverse > 2) ++pinched;
    }
    EXPECT_LT(double(pinched), 1e-3 * double(edges));
    EXPECT_TRUE(allVerticesUsed(got));
}
