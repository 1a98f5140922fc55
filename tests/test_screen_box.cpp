// Screen boxes of world boxes: the SAGE estimate (§3.4, Fig. 6) always contains the exact
// 8-corner box, which agrees with Camera::project; near-plane handling; and the Fig. 4
// sub-pixel point rule; the per-cell boxes and vertex positions of a meta-cell's projected corners.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>
#include <random>

#include <glm/geometric.hpp>

#include "core/camera.h"
#include "core/simd.h"
#include "core/view/corner_projection.h"
#include "core/view/screen_box.h"
#include "core/volume.h"

namespace vdiso {
namespace {

glm::dvec3 corner(const glm::dvec3& lo, const glm::dvec3& hi, int i) {
    return {i & 1 ? hi.x : lo.x, i & 2 ? hi.y : lo.y, i & 4 ? hi.z : lo.z};
}

// BoxProjector::outsideBox(): nothing of the box is in the view frustum.
bool outside(const ScreenBox& b) { return !b.crossesNearPlane && b.left == std::numeric_limits<double>::infinity(); }

// Whether the point lies in the camera's view frustum (OpenGL clip space, planes included).
bool inFrustum(const Camera& c, const glm::dvec3& p) {
    const glm::dvec4 q = c.viewProjection() * glm::dvec4(p, 1.0);
    return std::abs(q.x) <= q.w && std::abs(q.y) <= q.w && std::abs(q.z) <= q.w;
}

// A camera around the unit box [0,1]^3, at distances from just outside it to far away.
Camera randomCamera(std::mt19937& rng) {
    std::uniform_real_distribution<double> unit(0.0, 1.0);
    std::normal_distribution<double> normal;
    const int sizes[][2] = {{640, 480}, {1024, 768}, {333, 517}, {64, 48}};
    Camera c;
    const auto& size = sizes[rng() % 4];
    c.width = size[0];
    c.height = size[1];
    c.fovYDegrees = 10.0 + 80.0 * unit(rng);
    c.target = glm::dvec3(0.5) + 0.3 * glm::dvec3(normal(rng), normal(rng), normal(rng));
    const glm::dvec3 dir = glm::normalize(glm::dvec3(normal(rng), normal(rng), normal(rng)));
    c.eye = c.target + dir * std::pow(10.0, 0.2 + 1.3 * unit(rng));  // 1.6 .. 32
    c.up = glm::dvec3(0.0, 0.0, 1.0);
    if (std::abs(dir.z) > 0.99) c.up = glm::dvec3(0.0, 1.0, 0.0);
    fitClipPlanes(c, glm::dvec3(-1.0), glm::dvec3(2.0));
    return c;
}

// A random box in front of the camera, mostly in view (some beyond the image edges), its size
// a fraction `relative` of its distance from the eye, or random when relative <= 0.
void randomBoxInView(std::mt19937& rng, const Camera& c, double relative, glm::dvec3& lo,
                     glm::dvec3& hi) {
    std::uniform_real_distribution<double> unit(0.0, 1.0);
    const double depth = c.zNear * 1.5 + unit(rng) * (c.zFar - c.zNear * 1.5);
    const glm::dvec3 pixel{unit(rng) * 1.4 - 0.2, unit(rng) * 1.4 - 0.2, 0.0};
    // Unproject a random pixel at the near plane and walk along its ray to the depth.
    const glm::dvec3 onNear = c.unproject({pixel.x * c.width, pixel.y * c.height, 0.0});
    const glm::dvec3 ray = glm::normalize(onNear - c.eye);
    const double along = depth / glm::dot(ray, c.forward());
    const glm::dvec3 centre = c.eye + ray * along;
    const double size =
        depth * (relative > 0.0 ? relative : std::pow(10.0, -3.0 + 2.5 * unit(rng)));
    const glm::dvec3 half =
        0.5 * size * glm::dvec3(0.3 + unit(rng), 0.3 + unit(rng), 0.3 + unit(rng));
    // Keep the whole box beyond the near plane: shrink it if a corner comes too near.
    lo = centre - half;
    hi = centre + half;
    for (int i = 0; i < 8; ++i) {
        if (glm::dot(corner(lo, hi, i) - c.eye, c.forward()) <= c.zNear * 1.01) {
            lo = centre - 0.1 * half * (depth - c.zNear) / glm::length(half);
            hi = centre + 0.1 * half * (depth - c.zNear) / glm::length(half);
            break;
        }
    }
}

double area(const ScreenBox& b) { return b.width() * b.height(); }

TEST(ScreenBox, EstimateContainsExactAndExactMatchesCameraProject) {
    std::mt19937 rng(42);
    int boxes = 0;
    for (int cam = 0; cam < 200; ++cam) {
        const Camera c = randomCamera(rng);
        const BoxProjector projector(c);
        for (int b = 0; b < 30; ++b) {
            glm::dvec3 lo, hi;
            randomBoxInView(rng, c, 0.0, lo, hi);
            const ScreenBox exact = projector.exactBox(lo, hi);
            const ScreenBox estimate = projector.estimateBox(lo, hi);
            ASSERT_FALSE(exact.crossesNearPlane);
            ASSERT_FALSE(estimate.crossesNearPlane);
            ++boxes;

            double left = 1e300, right = -1e300, top = 1e300, bottom = -1e300;
            for (int i = 0; i < 8; ++i) {
                const glm::dvec3 p = c.project(corner(lo, hi, i));
                left = std::min(left, p.x);
                right = std::max(right, p.x);
                top = std::min(top, p.y);
                bottom = std::max(bottom, p.y);
            }
            const double scale = 1.0 + std::max({std::abs(left), std::abs(right),
                                                 std::abs(top), std::abs(bottom)});
            const double tol = 1e-9 * scale;
            ASSERT_NEAR(exact.left, left, tol);
            ASSERT_NEAR(exact.right, right, tol);
            ASSERT_NEAR(exact.top, top, tol);
            ASSERT_NEAR(exact.bottom, bottom, tol);

            ASSERT_LE(estimate.left, exact.left + tol) << "camera " << cam << " box " << b;
            ASSERT_GE(estimate.right, exact.right - tol);
            ASSERT_LE(estimate.top, exact.top + tol);
            ASSERT_GE(estimate.bottom, exact.bottom - tol);
            ASSERT_LE(exact.left, exact.right);
            ASSERT_LE(exact.top, exact.bottom);
        }
    }
    EXPECT_EQ(boxes, 6000);
}

// A meta-cell's corners projected once (core/view/corner_projection.h): each cell's box holds
// the exact box of the cell's world box (and is it, but for the slack), a point placed on an edge
// is Camera::project's pixel of that point, and a corner shared by two meta-cells places the
// points of its edges with the same bits from either.
TEST(CornerProjection, CellBoxesAreExactAndSharedEdgesPlaceTheSameBits) {
    std::mt19937 rng(7);
    std::uniform_real_distribution<double> unit(0.0, 1.0);
    constexpr int M = 4;
    uint64_t rows[(M + 1) * (M + 1)];
    std::fill_n(rows, (M + 1) * (M + 1), (uint64_t(1) << (M + 1)) - 1);
    int boxes = 0, points = 0;
    for (int cam = 0; cam < 100; ++cam) {
        const Camera c = randomCamera(rng);
        VolumeInfo grid;
        grid.spacing = glm::dvec3(0.002 + 0.02 * unit(rng), 0.002 + 0.02 * unit(rng), 0.002 + 0.02 * unit(rng));
        grid.origin = glm::dvec3(unit(rng), unit(rng), unit(rng)) - 0.5;
        const glm::dmat4 gridToClip = c.viewProjection() * grid.gridToWorld();
        const BoxProjector world(c);
        CornerProjection a(gridToClip, c.width, c.height, M), b(gridToClip, c.width, c.height, M);
        for (int m = 0; m < 10; ++m) {
            const int64_t first[3] = {int64_t(unit(rng) * 56), int64_t(unit(rng) * 56), int64_t(unit(rng) * 56)};
            const int64_t next[3] = {first[0] + M, first[1], first[2]};  // the meta-cell beside it in x
            a.project(first, rows);
            b.project(next, rows);
            for (int z = 0; z < M; ++z)
                for (int y = 0; y < M; ++y)
                    for (int x = 0; x < M; ++x) {
                        const glm::dvec3 cell{double(first[0] + x), double(first[1] + y), double(first[2] + z)};
                        const glm::dvec3 lo = grid.origin + cell * grid.spacing, hi = lo + grid.spacing;
                        const ScreenBox e = world.exactBox(lo, hi), box = a.cellBox(x, y, z);
                        // Eight corners behind the near plane: the world box is outside too. One
                        // outside beside the frustum while reaching the near plane: the cell is
                        // only refined (its corners are not all behind).
                        if (outside(box)) {
                            EXPECT_TRUE(outside(e));
                            continue;
                        }
                        if (outside(e)) {
                            EXPECT_TRUE(box.crossesNearPlane);
                            continue;
                        }
                        ASSERT_EQ(box.crossesNearPlane, e.crossesNearPlane);
                        if (e.crossesNearPlane) continue;
                        ++boxes;
                        const double tol = 1e-9 * (1.0 + std::abs(e.left) + std::abs(e.top) + std::abs(e.right) +
                                                   std::abs(e.bottom));
                        EXPECT_LE(box.left, e.left);
                        EXPECT_GE(box.right, e.right);
                        EXPECT_LE(box.top, e.top);
                        EXPECT_GE(box.bottom, e.bottom);
                        EXPECT_NEAR(box.left, e.left, tol + CornerProjection::kBoxSlack);
                        EXPECT_NEAR(box.bottom, e.bottom, tol + CornerProjection::kBoxSlack);
                    }
            // Points on every edge of the corners the two meta-cells share (x = M in a, 0 in b),
            // along y and z, and on a's edges along x.
            for (int z = 0; z < M; ++z)
                for (int y = 0; y < M; ++y)
                    for (int axis = 0; axis < 3; ++axis) {
                        const double t = unit(rng);
                        const int corner = a.cornerIndex(axis == 0 ? M - 1 : M, y, z);
                        glm::dvec2 pa, pb;
                        const bool placed = a.place(corner, axis, t, pa);
                        glm::dvec3 local{double(first[0] + (axis == 0 ? M - 1 : M)), double(first[1] + y),
                                         double(first[2] + z)};
                        local[axis] += t;
                        const glm::dvec3 expected = c.project(grid.origin + local * grid.spacing);
                        const bool projects = expected.z >= 0.0 && expected.z <= 1.0;
                        if (placed != projects) {  // only a hair from the near or far plane
                            EXPECT_LT(std::min(std::abs(expected.z), std::abs(expected.z - 1.0)), 1e-9);
                            continue;
                        }
                        if (!placed) continue;
                        ++points;
                        EXPECT_NEAR(pa.x, expected.x, 1e-7 * (1.0 + std::abs(expected.x)));
                        EXPECT_NEAR(pa.y, expected.y, 1e-7 * (1.0 + std::abs(expected.y)));
                        if (axis == 0) continue;
                        ASSERT_TRUE(b.place(b.cornerIndex(0, y, z), axis, t, pb));
                        EXPECT_EQ(std::memcmp(&pa, &pb, sizeof pa), 0) << pa.x << " " << pb.x;
                    }
        }
    }
    EXPECT_GT(boxes, 40000);
    EXPECT_GT(points, 30000);
}

TEST(ScreenBox, BoxesReachingTheNearPlaneCrossItUnlessWhollyOutside) {
    std::mt19937 rng(5);
    std::uniform_real_distribution<double> unit(0.0, 1.0);
    for (int cam = 0; cam < 300; ++cam) {
        const Camera c = randomCamera(rng);
        const BoxProjector projector(c);
        const glm::dvec3 f = c.forward();
        const double s = 0.01 + unit(rng);
        const glm::dvec3 half{s * (0.2 + unit(rng)), s * (0.2 + unit(rng)), s * (0.2 + unit(rng))};
        // Around the eye reaching past the near plane, and straddling it: refined. Wholly
        // behind the eye, and around the eye short of the near plane: culled.
        const glm::dvec3 centres[4] = {c.eye + 0.1 * (unit(rng) - 0.5) * s * f,
                                       c.eye + c.zNear * f + 0.05 * half * (unit(rng) - 0.5),
                                       c.eye - (3.0 + unit(rng)) * s * f, c.eye};
        const glm::dvec3 halves[4] = {half + 2.0 * c.zNear, half, half, 0.2 * c.zNear * half / s};
        for (int k = 0; k < 4; ++k) {
            const ScreenBox x = projector.exactBox(centres[k] - halves[k], centres[k] + halves[k]);
            const ScreenBox e = projector.estimateBox(centres[k] - halves[k], centres[k] + halves[k]);
            EXPECT_EQ(x.crossesNearPlane, k < 2) << k;
            EXPECT_EQ(e.crossesNearPlane, k < 2) << k;
            EXPECT_EQ(outside(x), k >= 2) << k;
            EXPECT_EQ(outside(e), k >= 2) << k;
            EXPECT_FALSE(isSubPixel(e));
            EXPECT_FALSE(subPixelPoint(e).has_value());
        }
    }
}

// A box reaching the near plane is culled only when no point of it lies in the frustum, and
// boxes beside the frustum or behind the near plane are culled (random boxes around the eye,
// each point of a 5^3 lattice over it tried).
TEST(ScreenBox, OnlyBoxesWhollyOutsideTheFrustumAreCulled) {
    std::mt19937 rng(17);
    std::uniform_real_distribution<double> unit(0.0, 1.0);
    std::normal_distribution<double> normal;
    int culled = 0, refined = 0;
    for (int cam = 0; cam < 200; ++cam) {
        const Camera c = randomCamera(rng);
        const BoxProjector projector(c);
        for (int b = 0; b < 50; ++b) {
            const double s = c.zNear * std::pow(10.0, 2.0 * unit(rng));
            const glm::dvec3 centre = c.eye + 2.0 * s * glm::dvec3(normal(rng), normal(rng), normal(rng));
            const glm::dvec3 half{s * unit(rng), s * unit(rng), s * unit(rng)};
            const ScreenBox x = projector.exactBox(centre - half, centre + half);
            const ScreenBox e = projector.estimateBox(centre - half, centre + half);
            if (!x.crossesNearPlane && !outside(x)) continue;
            EXPECT_EQ(outside(x), outside(e));
            bool seen = false;
            for (int i = 0; i < 125 && !seen; ++i) {
                const glm::dvec3 t{(i % 5) / 4.0, (i / 5 % 5) / 4.0, (i / 25) / 4.0};
                seen = inFrustum(c, centre - half + 2.0 * half * t);
            }
            if (seen) {
                EXPECT_FALSE(outside(x));
            }
            culled += outside(x);
            refined += x.crossesNearPlane;
        }
    }
    EXPECT_GT(culled, 1000);
    EXPECT_GT(refined, 200);
}

// A projected meta-cell's cells: wholly behind the near plane, culled (an empty rectangle); in
// part, refined (no rectangle).
TEST(CornerProjection, CellsBehindTheNearPlaneAreCulledCellsAcrossItRefined) {
    std::mt19937 rng(23);
    std::uniform_real_distribution<double> unit(0.0, 1.0);
    constexpr int M = 8, S = M + 1;
    uint64_t rows[S * S];
    std::fill_n(rows, S * S, (uint64_t(1) << S) - 1);
    int behind = 0, across = 0;
    for (int cam = 0; cam < 50; ++cam) {
        const Camera c = randomCamera(rng);
        VolumeInfo grid;
        grid.spacing = glm::dvec3(c.zNear * (0.2 + unit(rng)));
        grid.origin = c.eye - grid.spacing * double(M / 2) + c.forward() * c.zNear * (unit(rng) - 0.5);
        CornerProjection p(c.viewProjection() * grid.gridToWorld(), c.width, c.height, M);
        const int64_t first[3] = {0, 0, 0};
        p.project(first, rows);
        for (int z = 0; z < M; ++z)
            for (int y = 0; y < M; ++y)
                for (int x = 0; x < M; ++x) {
                    int front = 0, back = 0;
                    for (int k = 0; k < 8; ++k) {
                        const glm::dvec3 g{double(x + (k & 1)), double(y + (k >> 1 & 1)), double(z + (k >> 2))};
                        const glm::dvec4 q = c.viewProjection() * glm::dvec4(grid.origin + g * grid.spacing, 1.0);
                        front += q.z + q.w > 1e-9 * q.w;
                        back += q.z + q.w < -1e-9 * std::abs(q.w);
                    }
                    if (front + back < 8 || front == 8) continue;  // a hair from the plane, or in front
                    PixelRect r{};
                    const bool rect = p.cellRect(x, y, z, r);
                    if (back == 8) {
                        ++behind;
                        EXPECT_TRUE(rect);
                        EXPECT_TRUE(r.empty());
                        EXPECT_TRUE(outside(p.cellBox(x, y, z)));
                    } else {
                        ++across;
                        EXPECT_FALSE(rect);
                        EXPECT_TRUE(p.cellBox(x, y, z).crossesNearPlane);
                    }
                }
    }
    EXPECT_GT(behind, 1000);
    EXPECT_GT(across, 100);
}

TEST(ScreenBox, EstimateIsTightForSmallDistantBoxes) {
    std::mt19937 rng(11);
    const double relativeSizes[] = {0.01, 0.1};
    double meanRatio[2] = {0.0, 0.0}, worstRatio[2] = {0.0, 0.0}, meanSlack[2] = {0.0, 0.0};
    for (int k = 0; k < 2; ++k) {
        int n = 0;
        for (int cam = 0; cam < 100; ++cam) {
            const Camera c = randomCamera(rng);
            const BoxProjector projector(c);
            for (int b = 0; b < 20; ++b) {
                glm::dvec3 lo, hi;
                randomBoxInView(rng, c, relativeSizes[k], lo, hi);
                const ScreenBox exact = projector.exactBox(lo, hi);
                const ScreenBox estimate = projector.estimateBox(lo, hi);
                const double ratio = area(estimate) / area(exact);
                meanSlack[k] += 0.25 * (exact.left - estimate.left + estimate.right -
                                        exact.right + exact.top - estimate.top +
                                        estimate.bottom - exact.bottom);
                meanRatio[k] += ratio;
                worstRatio[k] = std::max(worstRatio[k], ratio);
                ++n;
            }
        }
        meanRatio[k] /= n;
        meanSlack[k] /= n;
        std::printf("[ estimate ] boxes of %.2f x distance: area estimate / exact mean %.3f, "
                    "worst %.3f; mean slack per side %.3f px\n",
                    relativeSizes[k], meanRatio[k], worstRatio[k], meanSlack[k]);
    }
    // The w range is decoupled from the x and y ranges, so off-centre boxes in wide views
    // gain most; measured means about 1.5 (1/100) with this seed and camera mix.
    EXPECT_LT(meanRatio[0], 1.75);
    EXPECT_LT(worstRatio[0], 6.0);
    EXPECT_LT(meanRatio[1], 2.0);
}

// Fig. 4 on the x axis; y gets the same rule. Pixel 3 has its centre at 3.5.
TEST(ScreenBox, SubPixelPointFollowsFigure4) {
    auto box = [](double left, double right, double top, double bottom) {
        return ScreenBox{left, right, top, bottom, false};
    };
    // A: left in the left half of pixel 3, right past its centre.
    EXPECT_EQ(subPixelPoint(box(3.2, 4.1, 7.2, 8.1)), glm::ivec2(3, 7));
    // B: left in the right half of pixel 3 (past its centre): the centre is pixel 4's, and the
    // box is almost two pixels wide yet covers that one centre only.
    EXPECT_EQ(subPixelPoint(box(3.7, 5.4, 7.7, 9.4)), glm::ivec2(4, 8));
    // C: between two centres, none covered.
    EXPECT_FALSE(subPixelPoint(box(3.6, 4.4, 7.2, 8.1)).has_value());
    // Two centres (3.5 and 4.5) covered: not a point; the caller refines.
    EXPECT_FALSE(subPixelPoint(box(3.4, 4.6, 7.2, 8.1)).has_value());
    // One axis fails, the other holds: no point.
    EXPECT_FALSE(subPixelPoint(box(3.2, 4.1, 7.6, 8.4)).has_value());
    // Not sub-pixel (two pixels wide).
    EXPECT_FALSE(isSubPixel(box(3.0, 5.0, 7.2, 8.1)));
    EXPECT_FALSE(subPixelPoint(box(3.0, 5.0, 7.2, 8.1)).has_value());
    // Hanging over the left image border, the centre at 0.5 (floor, not trunc).
    EXPECT_EQ(subPixelPoint(box(-0.3, 0.9, 0.2, 0.8)), glm::ivec2(0, 0));
    // trunc would take -0.7 to 0 and answer pixel 0; the box covers -0.5 and 0.5: two centres.
    EXPECT_FALSE(subPixelPoint(box(-0.7, 0.6, 0.2, 0.8)).has_value());
}

// Exhaustive over a 1/16 pixel grid: a point's centre lies strictly inside the box and is the
// only centre in (left, right] (a centre exactly at left does not count, one at right does);
// a box covering no centre, or two, gives no point.
TEST(ScreenBox, SubPixelPointIsTheOnlyCoveredCentre) {
    int points = 0;
    for (int l16 = -40; l16 <= 80; ++l16) {
        for (int w16 = 0; w16 < 32; ++w16) {
            const double left = l16 / 16.0, right = left + w16 / 16.0;
            const ScreenBox b{left, right, 1.1, 1.2, false};  // y: the centre 1.5 not covered
            EXPECT_FALSE(subPixelPoint(b).has_value());
            const ScreenBox both{left, right, left, right, false};
            const auto p = subPixelPoint(both);
            int inClosed = 0, inRule = 0;  // centres k + 0.5 in [left, right], (left, right]
            for (int k = -5; k <= 10; ++k) {
                inClosed += left <= k + 0.5 && k + 0.5 <= right;
                inRule += left < k + 0.5 && k + 0.5 <= right;
            }
            if (inClosed == 0 || inRule >= 2) {
                EXPECT_FALSE(p.has_value()) << left << " " << right;
            }
            if (p) {
                ++points;
                EXPECT_EQ(p->x, p->y);
                const double c = p->x + 0.5;
                EXPECT_LT(left, c);
                EXPECT_LT(c, right);
                EXPECT_EQ(inRule, 1) << left << " " << right;
            } else if (inRule == 1) {
                EXPECT_EQ(right - std::floor(right), 0.5) << left << " " << right;  // c == right
            }
        }
    }
    EXPECT_GT(points, 1000);
}

// CornerProjection's paths (core/simd.h) project the same bits: every cell's box (and whether a
// corner is behind the near plane) and every edge's placed point, for random rows of corners of
// grids in view and of grids around the eye.
TEST(CornerProjection, EveryPathProjectsTheSameBits) {
    if (!simdLevelRuns(SimdLevel::Avx2)) GTEST_SKIP() << "the CPU runs the baseline only";
    std::mt19937 rng(11);
    std::uniform_real_distribution<double> unit(0.0, 1.0);
    constexpr int M = 8, S = M + 1;
    int boxes = 0, behind = 0, points = 0;
    for (int cam = 0; cam < 60; ++cam) {
        const Camera c = randomCamera(rng);
        VolumeInfo grid;
        grid.spacing = glm::dvec3(0.002 + 0.05 * unit(rng), 0.002 + 0.05 * unit(rng), 0.002 + 0.05 * unit(rng));
        // Half the grids around the eye: some corners behind it or the near plane.
        grid.origin = cam % 2 ? c.eye - grid.spacing * 36.0 : glm::dvec3(unit(rng), unit(rng), unit(rng)) - 0.5;
        const glm::dmat4 gridToClip = c.viewProjection() * grid.gridToWorld();
        CornerProjection base(gridToClip, c.width, c.height, M, SimdLevel::Baseline);
        CornerProjection wide(gridToClip, c.width, c.height, M, SimdLevel::Avx2);
        for (int m = 0; m < 20; ++m) {
            const int64_t first[3] = {int64_t(unit(rng) * 64), int64_t(unit(rng) * 64), int64_t(unit(rng) * 64)};
            uint64_t rows[S * S];
            for (uint64_t& r : rows) r = m % 4 == 0 ? (uint64_t(1) << S) - 1 : rng() & ((uint64_t(1) << S) - 1);
            base.project(first, rows);
            wide.project(first, rows);
            auto has = [&](int x, int y, int z) { return rows[z * S + y] >> x & 1; };
            for (int z = 0; z < M; ++z)
                for (int y = 0; y < M; ++y)
                    for (int x = 0; x < M; ++x) {
                        bool all = true;
                        for (int k = 0; k < 8; ++k) all = all && has(x + (k & 1), y + (k >> 1 & 1), z + (k >> 2));
                        if (!all) continue;
                        const ScreenBox a = base.cellBox(x, y, z), b = wide.cellBox(x, y, z);
                        ASSERT_EQ(a.crossesNearPlane, b.crossesNearPlane);
                        behind += a.crossesNearPlane || outside(a);
                        ++boxes;
                        EXPECT_EQ(std::memcmp(&a.left, &b.left, sizeof a.left), 0);
                        EXPECT_EQ(std::memcmp(&a.right, &b.right, sizeof a.right), 0);
                        EXPECT_EQ(std::memcmp(&a.top, &b.top, sizeof a.top), 0);
                        EXPECT_EQ(std::memcmp(&a.bottom, &b.bottom, sizeof a.bottom), 0);
                    }
            for (int z = 0; z <= M; ++z)
                for (int y = 0; y <= M; ++y)
                    for (int x = 0; x <= M; ++x)
                        for (int axis = 0; axis < 3; ++axis) {
                            const int to[3] = {x + (axis == 0), y + (axis == 1), z + (axis == 2)};
                            if (to[axis] > M || !has(x, y, z) || !has(to[0], to[1], to[2])) continue;
                            const double t = unit(rng);
                            glm::dvec2 pa, pb;
                            const int corner = base.cornerIndex(x, y, z);
                            ASSERT_EQ(base.place(corner, axis, t, pa), wide.place(corner, axis, t, pb));
                            ++points;
                            EXPECT_EQ(std::memcmp(&pa, &pb, sizeof pa), 0);
                        }
        }
    }
    EXPECT_GT(boxes, 1000);
    EXPECT_GT(behind, 10);
    EXPECT_GT(points, 10000);
}

}  // namespace
}  // namespace vdiso
