// core/kernel/trilinear_cell.h: a cell cut as its trilinear interpolant. The face cuts chain
// into loops for every choice of ambiguous faces, and with none chosen they are the tables';
// a cell whose case cannot differ is cut as the tables cut it; every cut's boundary is its
// loops' edges, each once and in their direction (so neighbours weld and the surface stays
// oriented); the pieces of each side joined inside the cell agree with a dense sampling of
// the interpolant; and a volume of noise extracted so is a closed, consistently wound surface.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <set>
#include <vector>

#include "core/extract/extract_full.h"
#include "core/kernel/mc_tables.h"
#include "core/kernel/trilinear_cell.h"
#include "tests/extract_test_util.h"

namespace vdiso {
namespace {

TEST(TrilinearCell, NonFiniteSamplesAreCutAsTheTablesCutThem) {
    const double f[8] = {1.0, -1.0, -1.0, 1.0, std::numeric_limits<double>::infinity(), -1.0, -1.0,
                         std::numeric_limits<double>::quiet_NaN()};
    int c = 0;
    for (int k = 0; k < 8; ++k) c |= int(f[k] > 0) << k;
    TrilinearCell cut;
    trilinearCell(f, cut);
    const McTriangleCase& t = mcTriangleCase(c);
    ASSERT_EQ(cut.triangleCount, t.triangleCount);
    EXPECT_EQ(cut.centreCount, 0);
    for (int k = 0; k < 3 * t.triangleCount; ++k) EXPECT_EQ(cut.edges[k], t.edges[k]);
}

TEST(TrilinearCell, FaceCutsChainForEveryChoiceAndNoneIsTheTables) {
    for (int c = 0; c < kMcCaseCount; ++c) {
        const int ambiguous = mcAmbiguousFaces(c);
        McPolygonCase tables;
        ASSERT_TRUE(mcPolygonsJoined(c, 0, tables));
        const McPolygonCase& expected = mcPolygonCase(c);
        ASSERT_EQ(tables.polygonCount, expected.polygonCount) << c;
        for (int e = 0; e < kMcEdgeCount; ++e) ASSERT_EQ(tables.edges[e], expected.edges[e]) << c;
        for (int mask = ambiguous; mask; mask = (mask - 1) & ambiguous) {
            McPolygonCase cut;
            ASSERT_TRUE(mcPolygonsJoined(c, mask, cut)) << c << " " << mask;
            int edges = 0;
            for (int p = 0; p < cut.polygonCount; ++p) edges += cut.vertexCount[p];
            EXPECT_EQ(edges, __builtin_popcount(mcCrossedEdges(c))) << c << " " << mask;
        }
    }
}

// The directed boundary edges (pairs of cell edges) of a cut's triangles: those not matched by
// the same pair in the other direction.
std::multiset<std::pair<int, int>> boundary(const TrilinearCell& cut) {
    std::multiset<std::pair<int, int>> directed;
    for (int t = 0; t < cut.triangleCount; ++t)
        for (int k = 0; k < 3; ++k) directed.insert({cut.edges[3 * t + k], cut.edges[3 * t + (k + 1) % 3]});
    std::multiset<std::pair<int, int>> open;
    for (const auto& [a, b] : directed) {
        auto back = directed.find({b, a});
        if (back == directed.end()) open.insert({a, b});
    }
    return open;
}

// Which sides' pieces the interpolant joins, by flood fill of a dense sampling: the number of
// pieces of the cube's side `above` among the grid's points.
int densePieces(const double f[8], bool above, int n) {
    auto value = [&](int i, int j, int k) {
        const double x = double(i) / (n - 1), y = double(j) / (n - 1), z = double(k) / (n - 1);
        double v = 0;
        for (int c = 0; c < 8; ++c)
            v += f[c] * (c & 1 ? x : 1 - x) * (c & 2 ? y : 1 - y) * (c & 4 ? z : 1 - z);
        return v;
    };
    std::vector<int> label(size_t(n) * n * n, -1);
    int pieces = 0;
    for (int start = 0; start < n * n * n; ++start) {
        const int i0 = start % n, j0 = start / n % n, k0 = start / (n * n);
        if (label[size_t(start)] != -1 || (value(i0, j0, k0) > 0) != above) continue;
        std::vector<int> stack{start};
        label[size_t(start)] = pieces;
        while (!stack.empty()) {
            const int at = stack.back();
            stack.pop_back();
            const int i = at % n, j = at / n % n, k = at / (n * n);
            const int d[6][3] = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
            for (const auto& s : d) {
                const int a = i + s[0], b = j + s[1], c = k + s[2];
                if (a < 0 || b < 0 || c < 0 || a >= n || b >= n || c >= n) continue;
                const int next = (c * n + b) * n + a;
                if (label[size_t(next)] != -1 || (value(a, b, c) > 0) != above) continue;
                label[size_t(next)] = pieces;
                stack.push_back(next);
            }
        }
        ++pieces;
    }
    return pieces;
}

// The surface pieces of a cut (triangles joined through shared edge crossings).
int surfacePieces(const TrilinearCell& cut) {
    int parent[kTrilinearCentre + kTrilinearMaxCentres];  // edges and the vertices inside
    for (int e = 0; e < kTrilinearCentre + kTrilinearMaxCentres; ++e) parent[e] = e;
    auto find = [&](int e) {
        while (parent[e] != e) e = parent[e];
        return e;
    };
    std::set<int> used;
    for (int t = 0; t < cut.triangleCount; ++t)
        for (int k = 0; k < 3; ++k) {
            used.insert(cut.edges[3 * t + k]);
            parent[find(cut.edges[3 * t + k])] = find(cut.edges[3 * t]);
        }
    std::set<int> roots;
    for (int e : used) roots.insert(find(e));
    return int(roots.size());
}

TEST(TrilinearCell, CutsAreBoundedByTheirLoopsAndJoinWhatTheInterpolantJoins) {
    std::mt19937 rng(11);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    int tubes = 0, checked = 0, tubesChecked = 0, differs = 0;
    for (int trial = 0; trial < 60000; ++trial) {
        double f[8];
        int c = 0;
        for (int k = 0; k < 8; ++k) {
            f[k] = u(rng);
            c |= int(f[k] > 0) << k;
        }
        if (c == 0 || c == 255) continue;
        TrilinearCell cut;
        trilinearCell(f, cut);
        ASSERT_FALSE(cut.unresolved) << "case " << c;
        differs += trilinearMayDiffer(c);  // (the others the kernel takes from the tables)
        // The boundary: the loops' segments, each once, in their direction.
        int joinAbove = 0;  // the loops as cut: read back from which faces the boundary crosses
        std::multiset<std::pair<int, int>> open = boundary(cut);
        bool matched = false;
        const int ambiguous = mcAmbiguousFaces(c);
        for (int mask = ambiguous;; mask = (mask - 1) & ambiguous) {
            McPolygonCase loops;
            mcPolygonsJoined(c, mask, loops);
            std::multiset<std::pair<int, int>> segments;
            for (int p = 0, at = 0; p < loops.polygonCount; at += loops.vertexCount[p++])
                for (int k = 0; k < loops.vertexCount[p]; ++k)
                    segments.insert({loops.edges[at + k], loops.edges[at + (k + 1) % loops.vertexCount[p]]});
            if (segments == open) {
                matched = true;
                joinAbove = mask;
                break;
            }
            if (mask == 0) break;
        }
        ASSERT_TRUE(matched) << "case " << c << ": the cut's boundary is no choice of face cuts";
        McPolygonCase loops;
        mcPolygonsJoined(c, joinAbove, loops);
        // A tube joins two loops: fewer surface pieces than loops.
        const int pieces = surfacePieces(cut);
        tubes += pieces < loops.polygonCount;
        // Against a dense sampling: every piece of surface (disc or tube) parts the cube once
        // more, so the pieces of both sides number one more than the pieces of surface. Checked
        // on cells a 24^3 and a 40^3 grid agree on, and whose faces' deciders are not within a
        // sampling's reach of a tie (the grids cannot see a saddle that nearly touches the level).
        bool clear = true;
        for (int face = 0; face < 6; ++face) {
            const auto& q = mcFaceCorners()[size_t(face)];
            const double d = f[q[0]] * f[q[2]] - f[q[1]] * f[q[3]];
            clear = clear && !((ambiguous >> face & 1) && std::abs(d) < 0.02);
        }
        if (trilinearMayDiffer(c) && (trial % 12 == 0 || pieces < loops.polygonCount) && clear) {
            const int coarse = densePieces(f, true, 20) + densePieces(f, false, 20);
            const int fine = densePieces(f, true, 32) + densePieces(f, false, 32);
            if (coarse == fine) {
                ++checked;
                tubesChecked += pieces < loops.polygonCount;
                EXPECT_EQ(fine, 1 + pieces) << "case " << c << " f " << f[0] << " " << f[1] << " " << f[2] << " "
                                            << f[3] << " " << f[4] << " " << f[5] << " " << f[6] << " " << f[7];
            }
        }
    }
    EXPECT_GT(differs, 5000);
    EXPECT_GT(tubes, 50);
    EXPECT_GT(checked, 1000);
    EXPECT_GT(tubesChecked, 50);
}

// A full extraction asked for the trilinear cut (FullExtractOptions::trilinear), on noise:
// closed and consistently wound inside the volume, with vertices inside cells; the same mesh on
// one thread and on two (the count pass counts what the emission makes), bricks taken whole
// (32 cells) or meta-cell by meta-cell (64); and without the flag, the tables' mesh.
TEST(TrilinearCell, FullExtractionsCutSoAreClosedAndTheSameOnAnyThreads) {
    auto noise = [](int64_t x, int64_t y, int64_t z) {
        uint64_t h = uint64_t(x) * 73856093u ^ uint64_t(y) * 19349663u ^ uint64_t(z) * 83492791u;
        h = (h ^ (h >> 13)) * 0x5bd1e995u;
        return double((h ^ (h >> 15)) % 1000) / 1000.0;
    };
    for (const int brick : {32, 64}) {
        test::MemoryBrickSource source({70, 66, 40}, ScalarType::F32, brick, noise);
        FullExtractOptions options;
        options.iso = 0.5;
        TriangleMesh tables, one, two;
        extractOctree(source, options, tables);
        options.trilinear = true;
        extractOctree(source, options, one);
        options.threads = 2;
        extractOctree(source, options, two);
        EXPECT_EQ(test::checkClosedOriented(one, &source.volume()), "") << brick;
        EXPECT_NE(one.triangleCount(), tables.triangleCount()) << brick;
        EXPECT_GT(one.vertexCount(), tables.vertexCount()) << brick;  // vertices inside cells
        EXPECT_EQ(one.positions, two.positions) << brick;
        EXPECT_EQ(one.normals, two.normals) << brick;
        EXPECT_EQ(one.indices, two.indices) << brick;
        for (const glm::vec3& n : one.normals) ASSERT_NEAR(glm::length(n), 1.0f, 1e-4f);
    }
}

}  // namespace
}  // namespace vdiso
