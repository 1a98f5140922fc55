// core/view/pixel_rect.h: the box, cell and polygon rectangles rounded two coordinates at a time
// are the integers the scalar roundings of the boxes give, on random points, points on and a
// hair beside pixel centres and pixel edges, and points far off the image.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

#include "core/view/corner_projection.h"
#include "core/view/pixel_round.h"
#include "core/view/pixel_rect.h"
#include "core/view/polygon_coverage.h"
#include "core/view/screen_box.h"

namespace vdiso {
namespace {

// The scalar rules, one coordinate at a time: the centres of a box (as ViewCuller rounded
// them), then clamped to the image as OcclusionPyramid::isOccluded clamps; the slack rectangle
// of a polygon's box as PolygonCoverage rounded it; and centresOfBox.
PixelRect boxRule(const ScreenBox& box, int width, int height) {
    const double w = width, h = height;
    return {ceilToInt(std::clamp(box.left - 0.5, -1.0, w)), ceilToInt(std::clamp(box.top - 0.5, -1.0, h)),
            floorToInt(std::clamp(box.right - 0.5, -1.0, w)), floorToInt(std::clamp(box.bottom - 0.5, -1.0, h))};
}
PixelRect onImage(const PixelRect& r, int width, int height) {
    return {std::max(r.x0, 0), std::max(r.y0, 0), std::min(r.x1, width - 1), std::min(r.y1, height - 1)};
}
PixelRect slackRule(const ScreenBox& box, int width, int height) {
    const double w = width, h = height;
    return {ceilToInt(std::clamp(box.left - kRasterSlack - 0.5, 0.0, w)),
            ceilToInt(std::clamp(box.top - kRasterSlack - 0.5, 0.0, h)),
            floorToInt(std::clamp(box.right + kRasterSlack - 0.5, -1.0, w - 1)),
            floorToInt(std::clamp(box.bottom + kRasterSlack - 0.5, -1.0, h - 1))};
}

bool same(const PixelRect& a, const PixelRect& b) { return a.x0 == b.x0 && a.y0 == b.y0 && a.x1 == b.x1 && a.y1 == b.y1; }

// Coordinates that lie on the roundings' edges: pixel centres and edges, a hair either side of
// them and of them widened by the slacks, off the image, and random ones.
double coordinate(std::mt19937_64& rng, int side) {
    std::uniform_int_distribution<int> kind(0, 5), pixel(-3, side + 3);
    std::uniform_real_distribution<double> any(-2.0 * side, 3.0 * side);
    const double base = pixel(rng);
    switch (kind(rng)) {
        case 0: return base + 0.5;
        case 1: return base;
        case 2: return std::nextafter(base + 0.5, rng() & 1 ? 1e9 : -1e9);
        case 3: return base + 0.5 + ((rng() & 1) ? kRasterSlack : -kRasterSlack);
        case 4: return (rng() & 1) ? 1e12 : -1e12;
        default: return any(rng);
    }
}

TEST(PixelRect, BoxRectanglesAreTheScalarRoundingsToTheBit) {
    std::mt19937_64 rng(7);
    for (const int side : {1, 7, 64, 1000}) {
        const int width = side, height = side + 3;
        const ImageLanes image(width, height);
        for (int round = 0; round < 20000; ++round) {
            double x[2] = {coordinate(rng, width), coordinate(rng, width)};
            double y[2] = {coordinate(rng, height), coordinate(rng, height)};
            std::sort(x, x + 2);
            std::sort(y, y + 2);
            // A cell's box is its corners' widened by CornerProjection::kBoxSlack.
            for (const double slack : {0.0, CornerProjection::kBoxSlack}) {
                const ScreenBox box{x[0] - slack, x[1] + slack, y[0] - slack, y[1] + slack, false};
                const __m128d lo = _mm_setr_pd(box.left, box.top), hi = _mm_setr_pd(box.right, box.bottom);
                const PixelRect want = boxRule(box, width, height);
                ASSERT_TRUE(same(boxCentres(lo, hi, image), want))
                    << side << " box " << x[0] << "," << y[0] << " - " << x[1] << "," << y[1];
                ASSERT_TRUE(same(boxCentresOnImage(lo, hi, image), onImage(want, width, height)))
                    << side << " box " << x[0] << "," << y[0] << " - " << x[1] << "," << y[1];
            }
        }
    }
}

TEST(PixelRect, PolygonRectanglesAreTheScalarRoundingsToTheBit) {
    std::mt19937_64 rng(11);
    std::uniform_int_distribution<int> vertices(1, 7);
    for (const int side : {1, 7, 64, 1000}) {
        const int width = side + 2, height = side;
        const ImageLanes image(width, height);
        for (int round = 0; round < 20000; ++round) {
            std::vector<glm::dvec2> v(size_t(vertices(rng)));
            for (glm::dvec2& p : v) p = {coordinate(rng, width), coordinate(rng, height)};
            const ScreenBox box = boxOfPoints(v.data(), int(v.size()));
            PixelRect slack, centres;
            polygonRects(v.data(), int(v.size()), image, slack, centres);
            ASSERT_TRUE(same(slack, slackRule(box, width, height))) << side << " round " << round;
            ASSERT_TRUE(same(centres, centresOfBox(box, width, height))) << side << " round " << round;
        }
    }
}

}  // namespace
}  // namespace vdiso
