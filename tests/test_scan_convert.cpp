// Scan conversion at pixel centres (SAGE §3.2): against a brute-force winding number at every
// centre, exact sharing of edges between adjacent polygons, and the fan conservativeness claim.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <random>
#include <vector>

#include <glm/common.hpp>

#include "core/simd.h"
#include "core/view/occlusion_pyramid.h"
#include "core/view/pixel_round.h"
#include "core/view/polygon_coverage.h"
#include "core/view/scan_convert.h"
#include "core/view/screen_box.h"
#include "core/view/tile_coverage.h"

namespace vdiso {
namespace {

using Polygon = std::vector<glm::dvec2>;

// Winding number at p with the documented tie rules, by sign tests (products, no division):
// an edge counts when yTop <= p.y < yBottom, and its crossing counts when at or left of p.
int windingAt(const Polygon& poly, glm::dvec2 p) {
    int w = 0;
    for (size_t i = 0; i < poly.size(); ++i) {
        const glm::dvec2 a = poly[i], b = poly[(i + 1) % poly.size()];
        if (a.y <= p.y && p.y < b.y) {
            if ((p.y - a.y) * (b.x - a.x) <= (p.x - a.x) * (b.y - a.y)) ++w;
        } else if (b.y <= p.y && p.y < a.y) {
            if ((p.y - b.y) * (a.x - b.x) <= (p.x - b.x) * (a.y - b.y)) --w;
        }
    }
    return w;
}

struct Span {
    int y, x0, x1;
};

std::vector<Span> spansOf(const Polygon& poly, int width, int height) {
    std::vector<Span> spans;
    scanConvertPolygon(poly, width, height,
                       [&](int y, int x0, int x1) { spans.push_back({y, x0, x1}); });
    return spans;
}

// Checks the output contract and returns the covered pixels, row-major.
std::vector<int> coverageOf(const Polygon& poly, int width, int height) {
    const std::vector<Span> spans = spansOf(poly, width, height);
    std::vector<int> covered(size_t(width) * height, 0);
    for (size_t i = 0; i < spans.size(); ++i) {
        const Span& s = spans[i];
        EXPECT_GE(s.y, 0);
        EXPECT_LT(s.y, height);
        EXPECT_GE(s.x0, 0);
        EXPECT_LE(s.x0, s.x1);
        EXPECT_LT(s.x1, width);
        if (i > 0) {
            const Span& prev = spans[i - 1];
            EXPECT_TRUE(prev.y < s.y || (prev.y == s.y && prev.x1 + 1 < s.x0))
                << "spans out of order, overlapping or not maximal in row " << s.y;
        }
        if (s.y < 0 || s.y >= height) continue;
        for (int x = std::max(s.x0, 0); x <= std::min(s.x1, width - 1); ++x)
            covered[size_t(s.y) * width + x] += 1;
    }
    return covered;
}

std::vector<int> bruteForce(const Polygon& poly, int width, int height) {
    std::vector<int> covered(size_t(width) * height, 0);
    for (int y = 0; y < height; ++y)
        for (int x = 0; x < width; ++x)
            covered[size_t(y) * width + x] = windingAt(poly, {x + 0.5, y + 0.5}) != 0;
    return covered;
}

// Convex, star-shaped (concave) or self-intersecting polygons, sub-pixel to ~100 px. With
// `quantize`, coordinates lie on a 1/4 pixel grid, so that many centres fall exactly on edges
// and vertices and all the arithmetic is exact.
Polygon randomPolygon(std::mt19937& rng, int width, int height, bool quantize) {
    std::uniform_real_distribution<double> unit(0.0, 1.0);
    const int kind = int(unit(rng) * 3.0);
    const int n = 3 + int(unit(rng) * (unit(rng) < 0.1 ? 18.0 : 10.0));  // some above 16
    const double radius = std::pow(10.0, -0.5 + 2.5 * unit(rng));        // 0.3 .. 100
    const glm::dvec2 centre{-20.0 + unit(rng) * (width + 40.0),
                            -20.0 + unit(rng) * (height + 40.0)};
    Polygon poly;
    std::vector<double> angles(size_t(n), 0.0);
    for (double& a : angles) a = unit(rng) * 2.0 * std::numbers::pi;
    if (kind != 2) std::sort(angles.begin(), angles.end());
    for (int i = 0; i < n; ++i) {
        const double r = kind == 0 ? radius : radius * (0.2 + 0.8 * unit(rng));
        glm::dvec2 p = centre + r * glm::dvec2(std::cos(angles[size_t(i)]),
                                               std::sin(angles[size_t(i)]));
        if (quantize) p = glm::round(p * 4.0) / 4.0;
        poly.push_back(p);
    }
    return poly;
}

// The pixel rounding every test above relies on: std::ceil's and std::floor's results, at
// integers and half-integers, a hair either side of them, signed zeros, and random values over
// the clamped range.
TEST(PixelRound, IsCeilAndFloor) {
    std::vector<double> xs = {0.0, -0.0, 0.5, -0.5, 1.5, -1.5, 1023.5, 1e-300, -1e-300};
    for (int k = -3; k <= 2050; ++k)
        for (double base : {double(k), k + 0.5})
            xs.insert(xs.end(), {base, std::nextafter(base, -1e9), std::nextafter(base, 1e9)});
    std::mt19937_64 random(7);
    std::uniform_real_distribution<double> any(-2.0, 2050.0);
    for (int i = 0; i < 100000; ++i) xs.push_back(any(random));
    for (double x : xs) {
        ASSERT_EQ(ceilToInt(x), int(std::ceil(x))) << x;
        ASSERT_EQ(floorToInt(x), int(std::floor(x))) << x;
    }
}

TEST(ScanConvert, MatchesBruteForceWindingOnRandomPolygons) {
    std::mt19937 rng(12345);
    const int sizes[][2] = {{97, 61}, {1, 1}, {13, 40}};
    int coveredTotal = 0;
    for (const auto& size : sizes) {
        const int w = size[0], h = size[1];
        for (int trial = 0; trial < 400; ++trial) {
            const Polygon poly = randomPolygon(rng, w, h, trial % 2 == 0);
            const std::vector<int> got = coverageOf(poly, w, h);
            const std::vector<int> want = bruteForce(poly, w, h);
            for (size_t i = 0; i < got.size(); ++i) coveredTotal += got[i];
            ASSERT_EQ(got, want) << "image " << w << "x" << h << ", trial " << trial;
        }
    }
    EXPECT_GT(coveredTotal, 10000);  // the polygons did land on the images
}

TEST(ScanConvert, TwoTrianglesSharingAnEdgeCoverItsCentresOnce) {
    const int w = 20, h = 20;
    // Vertices on pixel centres; the shared edge a-b passes through centres (x, y) = (2.5 +
    // 2k, 1.5 + 3k).
    const glm::dvec2 a{2.5, 1.5}, b{14.5, 19.5}, c{0.5, 18.5}, d{17.5, 3.5};
    for (bool flip : {false, true}) {
        Polygon left{a, b, c}, right{a, d, b};
        if (flip) std::reverse(right.begin(), right.end());  // same edge, same direction
        const std::vector<int> l = coverageOf(left, w, h), r = coverageOf(right, w, h);
        const std::vector<int> quad = bruteForce({a, d, b, c}, w, h);
        for (int y = 0; y < h; ++y)
            for (int x = 0; x < w; ++x) {
                const size_t i = size_t(y) * w + x;
                ASSERT_EQ(l[i] + r[i], quad[i]) << "pixel " << x << "," << y;
            }
        for (int k = 1; k < 6; ++k) {  // centres strictly inside the shared edge
            const size_t i = size_t(1 + 3 * k) * w + size_t(2 + 2 * k);
            EXPECT_EQ(l[i] + r[i], 1) << "shared-edge centre " << k;
        }
    }
}

TEST(ScanConvert, SquareSplitEitherWayCoversEachCentreOnce) {
    const int w = 16, h = 16;
    const glm::dvec2 p00{2.5, 3.5}, p10{11.5, 3.5}, p11{11.5, 12.5}, p01{2.5, 12.5};
    const std::vector<int> square = bruteForce({p00, p10, p11, p01}, w, h);
    const Polygon splits[2][2] = {{{p00, p10, p11}, {p00, p11, p01}},
                                  {{p00, p10, p01}, {p10, p11, p01}}};
    for (const auto& split : splits) {
        const std::vector<int> s0 = coverageOf(split[0], w, h), s1 = coverageOf(split[1], w, h);
        for (size_t i = 0; i < square.size(); ++i) ASSERT_EQ(s0[i] + s1[i], square[i]) << i;
    }
    // Top-left rule: the top row and left column of the square's centres are in, the bottom row
    // and right column out. 9 x 9 centres.
    int total = 0;
    for (int v : square) total += v;
    EXPECT_EQ(total, 81);
    EXPECT_EQ(square[3 * w + 2], 1);
    EXPECT_EQ(square[12 * w + 2], 0);
    EXPECT_EQ(square[3 * w + 11], 0);
}

// A triangulated, jittered grid with vertices on pixel centres and random diagonals: every
// centre of the region is covered exactly once, and the union equals the outline's coverage.
TEST(ScanConvert, TriangulatedGridHasNoCracksAndNoOverlaps) {
    std::mt19937 rng(7);
    std::uniform_int_distribution<int> jitter(-1, 1);
    const int w = 64, h = 48, nx = 10, ny = 8, step = 8;  // step 8, jitter 1: convex quads
    for (int trial = 0; trial < 10; ++trial) {
        std::vector<glm::dvec2> grid(size_t(nx) * ny);
        for (int j = 0; j < ny; ++j)
            for (int i = 0; i < nx; ++i) {
                const bool border = i == 0 || j == 0 || i == nx - 1 || j == ny - 1;
                grid[size_t(j) * nx + i] = {-3.5 + step * i + (border ? 0 : jitter(rng)),
                                            -4.5 + step * j + (border ? 0 : jitter(rng))};
            }
        auto at = [&](int i, int j) { return grid[size_t(j) * nx + i]; };
        std::vector<int> count(size_t(w) * h, 0);
        for (int j = 0; j + 1 < ny; ++j)
            for (int i = 0; i + 1 < nx; ++i) {
                const glm::dvec2 q[4] = {at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1)};
                const int d = int(rng() & 1);
                const Polygon t0{q[d], q[d + 1], q[(d + 2) % 4]};
                const Polygon t1{q[d], q[(d + 2) % 4], q[(d + 3) % 4]};
                for (const Polygon& t : {t0, t1}) {
                    const std::vector<int> c = coverageOf(t, w, h);
                    for (size_t k = 0; k < c.size(); ++k) count[k] += c[k];
                }
            }
        const Polygon outline{at(0, 0), at(nx - 1, 0), at(nx - 1, ny - 1), at(0, ny - 1)};
        ASSERT_EQ(count, bruteForce(outline, w, h)) << "trial " << trial;
    }
}

// The reason for the nonzero rule: a centre the outline covers lies inside one of its fan
// triangles (the outline's winding is the sum of theirs), so polygon scan conversion never
// marks a pixel that the drawn triangles leave uncovered.
TEST(ScanConvert, OutlineCoverageLiesWithinItsFanTriangles) {
    std::mt19937 rng(99);
    const int w = 61, h = 47;
    int coveredCentres = 0;
    for (int trial = 0; trial < 300; ++trial) {
        const Polygon poly = randomPolygon(rng, w, h, trial % 2 == 0);
        const std::vector<int> outline = coverageOf(poly, w, h);
        std::vector<int> fanUnion(outline.size(), 0);
        std::vector<int> fanWindingSum(outline.size(), 0);
        for (size_t i = 1; i + 1 < poly.size(); ++i) {
            const Polygon tri{poly[0], poly[i], poly[i + 1]};
            const std::vector<int> c = coverageOf(tri, w, h);
            for (size_t k = 0; k < c.size(); ++k) fanUnion[k] |= c[k];
            if (trial % 2 == 0) {  // exact coordinates: the windings add up exactly
                for (int y = 0; y < h; ++y)
                    for (int x = 0; x < w; ++x)
                        fanWindingSum[size_t(y) * w + x] += windingAt(tri, {x + 0.5, y + 0.5});
            }
        }
        for (int y = 0; y < h; ++y)
            for (int x = 0; x < w; ++x) {
                const size_t k = size_t(y) * w + x;
                coveredCentres += outline[k];
                ASSERT_TRUE(!outline[k] || fanUnion[k])
                    << "trial " << trial << " " << x << "," << y;
                if (trial % 2 == 0) {
                    ASSERT_EQ(fanWindingSum[k], windingAt(poly, {x + 0.5, y + 0.5}));
                }
            }
    }
    EXPECT_GT(coveredCentres, 5000);
}

TEST(ScanConvert, ClipsToTheImageAndSurvivesHugeAndInvalidCoordinates) {
    const Polygon huge{{-1e12, -1e12}, {1e12, -1e12}, {0.0, 1e12}};
    const std::vector<int> c = coverageOf(huge, 10, 7);
    EXPECT_EQ(c, std::vector<int>(70, 1));
    const double nan = std::numeric_limits<double>::quiet_NaN();
    EXPECT_TRUE(spansOf({{1.0, 1.0}, {nan, nan}, {5.0, 6.0}}, 10, 7).empty());
    EXPECT_TRUE(spansOf({{1.0, 1.0}, {8.0, 1.0}}, 10, 7).empty());               // two vertices
    EXPECT_TRUE(spansOf({{1.0, 1.0}, {8.0, 1.0}, {3.0, 1.0}}, 10, 7).empty());   // flat
    EXPECT_TRUE(spansOf({{20.0, 1.0}, {28.0, 1.0}, {23.0, 6.0}}, 10, 7).empty());  // off right
}

TEST(ScanConvert, PyramidOverloadCoversTheSameSpans) {
    std::mt19937 rng(3);
    const int w = 83, h = 57;
    OcclusionPyramid pyramid(w, h);
    std::vector<int> model(size_t(w) * h, 0);
    for (int trial = 0; trial < 50; ++trial) {
        const Polygon poly = randomPolygon(rng, w, h, false);
        scanConvertPolygon(poly, pyramid);
        const std::vector<int> c = coverageOf(poly, w, h);
        for (size_t k = 0; k < c.size(); ++k) model[k] |= c[k];
    }
    pyramid.propagate();
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x)
            ASSERT_EQ(pyramid.isCovered(x, y), model[size_t(y) * w + x] != 0);
}

// Tile by tile, on every SIMD path this CPU runs (core/simd.h), the same bits as the rows and
// the same answer to "anything new?", over polygons from sub-pixel to a hundred pixels (many on
// quarter-pixel grids, so centres fall on edges and vertices), onto coverage left by earlier
// ones, on images whose last tiles are ragged; and a rectangle wider than the polygon's box
// changes nothing.
TEST(TileCoverage, EveryPathCoversWhatTheRowsCover) {
    std::vector<SimdLevel> paths;
    for (SimdLevel level : {SimdLevel::Baseline, SimdLevel::Avx2})
        if (simdLevelRuns(level)) paths.push_back(level);
    std::mt19937 rng(99);
    const int sizes[][2] = {{97, 61}, {8, 8}, {1, 1}, {13, 40}, {64, 9}};
    int newTotal = 0, tiled = 0;
    for (const auto& size : sizes) {
        const int w = size[0], h = size[1];
        OcclusionPyramid rows(w, h);
        std::vector<OcclusionPyramid> tiles(paths.size(), OcclusionPyramid(w, h));
        for (int trial = 0; trial < 1500; ++trial) {
            Polygon poly = randomPolygon(rng, w, h, trial % 2 == 0);
            if (trial % 3 == 0)  // a few pixels, where cells are about a pixel
                for (glm::dvec2& p : poly) p = poly[0] + (p - poly[0]) * (3.0 / 100.0);
            else if (trial % 3 == 1 && trial % 2 == 1)  // a pixel or two: one tile, one or two rows
                for (glm::dvec2& p : poly) p = poly[0] + (p - poly[0]) * (1.5 / 100.0);
            PixelRect r = centresOfBox(boxOfPoints(poly.data(), int(poly.size())), w, h);
            if (r.empty()) continue;
            if (trial % 5 == 0) r = {0, 0, w - 1, h - 1};
            const bool want = scanConvertPolygon(poly, rows);
            for (size_t k = 0; k < paths.size(); ++k) {
                bool got = false;
                if (!coverPolygonTiles(poly.data(), int(poly.size()), r, tiles[k], got, paths[k])) {
                    ASSERT_GT(poly.size(), size_t(kTileCoverageEdges));
                    got = scanConvertPolygon(poly, tiles[k]);
                } else {
                    ++tiled;
                }
                ASSERT_EQ(got, want) << simdLevelName(paths[k]) << ", image " << w << "x" << h << ", trial " << trial;
                ASSERT_TRUE(std::equal(rows.tiles().begin(), rows.tiles().end(), tiles[k].tiles().begin()))
                    << simdLevelName(paths[k]) << ", image " << w << "x" << h << ", trial " << trial;
            }
            newTotal += want;
            if (trial % 25 == 24) {  // start again from nothing now and then
                rows.clear();
                for (OcclusionPyramid& p : tiles) p.clear();
            }
        }
    }
    EXPECT_GT(newTotal, 400);
    EXPECT_GT(tiled, 1500 * int(paths.size()));
}

}  // namespace
}  // namespace vdiso
