// The occlusion pyramid against a brute-force coverage image: spans, rectangle queries, full
// bits at every level, and WISE's top-down triangle insertion against bottom-up scan conversion.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <random>
#include <vector>

#include <glm/common.hpp>

#include "core/view/occlusion_pyramid.h"
#include "core/view/scan_convert.h"

namespace vdiso {
namespace {

constexpr int kSizes[][2] = {{37, 23}, {64, 64}, {200, 131}, {1, 1}, {9, 8}, {520, 67}};

struct Model {
    int width, height;
    std::vector<uint8_t> covered;

    Model(int w, int h) : width(w), height(h), covered(size_t(w) * h, 0) {}
    // Returns whether a pixel was newly covered, as OcclusionPyramid::coverSpan does.
    bool coverSpan(int y, int x0, int x1) {
        if (y < 0 || y >= height) return false;
        bool changed = false;
        for (int x = std::max(x0, 0); x <= std::min(x1, width - 1); ++x) {
            changed |= !covered[size_t(y) * width + x];
            covered[size_t(y) * width + x] = 1;
        }
        return changed;
    }
    bool isOccluded(int x0, int y0, int x1, int y1) const {
        for (int y = std::max(y0, 0); y <= std::min(y1, height - 1); ++y)
            for (int x = std::max(x0, 0); x <= std::min(x1, width - 1); ++x)
                if (!covered[size_t(y) * width + x]) return false;
        return true;
    }
};

void expectSameCoverage(const OcclusionPyramid& p, const Model& m) {
    for (int y = 0; y < m.height; ++y)
        for (int x = 0; x < m.width; ++x)
            ASSERT_EQ(p.isCovered(x, y), m.covered[size_t(y) * m.width + x] != 0)
                << "pixel " << x << "," << y;
}

// Bits outside the image are set; a bit above the bottom is set exactly when the word below
// it is full (or does not exist); the top level is one word.
void expectConsistentLevels(const OcclusionPyramid& p) {
    for (int wy = 0; wy < p.wordsY(0); ++wy)
        for (int wx = 0; wx < p.wordsX(0); ++wx)
            for (int bit = 0; bit < 64; ++bit) {
                const int x = wx * 8 + bit % 8, y = wy * 8 + bit / 8;
                if (x >= p.width() || y >= p.height()) {
                    ASSERT_TRUE((p.word(0, wx, wy) >> bit) & 1)
                        << "padding pixel " << x << "," << y;
                }
            }
    for (int level = 1; level < p.levels(); ++level)
        for (int wy = 0; wy < p.wordsY(level); ++wy)
            for (int wx = 0; wx < p.wordsX(level); ++wx)
                for (int bit = 0; bit < 64; ++bit) {
                    const int cx = wx * 8 + bit % 8, cy = wy * 8 + bit / 8;
                    const bool exists = cx < p.wordsX(level - 1) && cy < p.wordsY(level - 1);
                    const bool want = !exists || p.word(level - 1, cx, cy) == ~uint64_t(0);
                    ASSERT_EQ(bool((p.word(level, wx, wy) >> bit) & 1), want)
                        << "level " << level << " word " << wx << "," << wy << " bit " << bit;
                }
    EXPECT_EQ(p.wordsX(p.levels() - 1), 1);
    EXPECT_EQ(p.wordsY(p.levels() - 1), 1);
}

TEST(OcclusionPyramid, LevelsGoUpToOneWord) {
    EXPECT_EQ(OcclusionPyramid(1, 1).levels(), 1);
    EXPECT_EQ(OcclusionPyramid(8, 8).levels(), 1);
    EXPECT_EQ(OcclusionPyramid(9, 8).levels(), 2);
    EXPECT_EQ(OcclusionPyramid(64, 64).levels(), 2);
    EXPECT_EQ(OcclusionPyramid(65, 3).levels(), 3);
    EXPECT_EQ(OcclusionPyramid(4096, 4096).levels(), 4);
    for (const auto& s : kSizes) expectConsistentLevels(OcclusionPyramid(s[0], s[1]));
}

TEST(OcclusionPyramid, SpansAndQueriesMatchBruteForce) {
    std::mt19937 rng(2024);
    std::uniform_real_distribution<double> unit(0.0, 1.0);
    int occludedAnswers = 0, visibleAnswers = 0;
    for (const auto& s : kSizes) {
        const int w = s[0], h = s[1];
        OcclusionPyramid pyramid(w, h);
        Model model(w, h);
        auto rand = [&](int lo, int hi) { return lo + int(unit(rng) * (hi - lo + 1)); };
        for (int round = 0; round < 12; ++round) {
            // Whole rectangles make large covered regions (so that high full bits matter);
            // loose spans leave holes in them.
            for (int r = 0; r < 4; ++r) {
                const int x0 = rand(-5, w), y0 = rand(-5, h);
                const int x1 = x0 + rand(0, w), y1 = y0 + rand(0, h / 2 + 1);
                for (int y = y0; y <= y1; ++y) {
                    pyramid.coverSpan(y, x0, x1);
                    model.coverSpan(y, x0, x1);
                }
            }
            for (int r = 0; r < 20; ++r) {
                const int y = rand(-2, h + 1), x0 = rand(-10, w + 2), x1 = x0 + rand(-2, 20);
                EXPECT_EQ(pyramid.coverSpan(y, x0, x1), model.coverSpan(y, x0, x1));
            }
            pyramid.propagate();
            EXPECT_FALSE(pyramid.hasPendingChanges());
            expectSameCoverage(pyramid, model);
            expectConsistentLevels(pyramid);

            for (int q = 0; q < 300; ++q) {
                int x0 = rand(-20, w + 20), y0 = rand(-20, h + 20);
                int x1 = x0 + rand(-3, w), y1 = y0 + rand(-3, h);
                switch (q % 10) {
                    case 0: x0 = 0, y0 = 0, x1 = w - 1, y1 = h - 1; break;     // whole image
                    case 1: x1 = x0, y1 = y0; break;                           // one pixel
                    case 2: x0 = -1000000, x1 = 1000000; break;                // wide
                    case 3: x0 = rand(0, w - 1), x1 = x0 + rand(0, 3); break;  // thin
                    case 4: case 5: x1 = x0 + rand(0, 8), y1 = y0 + rand(0, 8); break;  // within 2x2 tiles, often across
                    default: break;
                }
                const bool want = model.isOccluded(x0, y0, x1, y1);
                ASSERT_EQ(pyramid.isOccluded(x0, y0, x1, y1), want)
                    << w << "x" << h << " round " << round << " rect " << x0 << "," << y0
                    << " - " << x1 << "," << y1;
                (want ? occludedAnswers : visibleAnswers) += 1;
                // findUncovered visits exactly the uncovered pixels of the rectangle within the
                // image, each once, and stops at the first its callback accepts.
                const int cx0 = std::max(x0, 0), cy0 = std::max(y0, 0), cx1 = std::min(x1, w - 1), cy1 = std::min(y1, h - 1);
                if (cx0 > cx1 || cy0 > cy1) continue;
                std::vector<uint8_t> seen(size_t(w) * h, 0);
                size_t visits = 0;
                EXPECT_FALSE(pyramid.findUncovered(cx0, cy0, cx1, cy1, [&](int x, int y) {
                    ++visits;
                    seen[size_t(y) * w + x] += 1;
                    return false;
                }));
                size_t expected = 0;
                for (int y = cy0; y <= cy1; ++y)
                    for (int x = cx0; x <= cx1; ++x) {
                        const bool open = !model.covered[size_t(y) * w + x];
                        expected += open;
                        ASSERT_EQ(seen[size_t(y) * w + x], open ? 1 : 0) << x << "," << y;
                    }
                EXPECT_EQ(visits, expected);
                size_t untilFirst = 0;
                EXPECT_EQ(pyramid.findUncovered(cx0, cy0, cx1, cy1, [&](int, int) { return ++untilFirst == 1; }), expected > 0);
                EXPECT_EQ(untilFirst, std::min<size_t>(expected, 1));
            }
        }
        // Fill the image completely: every query is occluded, answered by the top word alone
        // (beyond 2x2 tiles, where words read are counted).
        for (int y = 0; y < h; ++y) pyramid.coverSpan(y, -3, w + 3);
        pyramid.propagate();
        expectConsistentLevels(pyramid);
        EXPECT_EQ(pyramid.word(pyramid.levels() - 1, 0, 0), ~uint64_t(0));
        const uint64_t wordsBefore = pyramid.stats().queryWords;
        EXPECT_TRUE(pyramid.isOccluded(0, 0, w - 1, h - 1));
        if (w > 16 || h > 16) EXPECT_EQ(pyramid.stats().queryWords, wordsBefore + 1);
        pyramid.clear();
        EXPECT_FALSE(pyramid.isCovered(0, 0));
        expectConsistentLevels(pyramid);
    }
    // Both answers were exercised plenty.
    EXPECT_GT(occludedAnswers, 1000);
    EXPECT_GT(visibleAnswers, 1000);
}

TEST(OcclusionPyramid, EmptyOrOffImageRectanglesAreOccluded) {
    const OcclusionPyramid pyramid(37, 23);
    EXPECT_TRUE(pyramid.isOccluded(5, 5, 4, 9));       // x1 < x0
    EXPECT_TRUE(pyramid.isOccluded(5, 5, 9, 4));       // y1 < y0
    EXPECT_TRUE(pyramid.isOccluded(37, 0, 50, 22));    // right of the image
    EXPECT_TRUE(pyramid.isOccluded(-9, -9, -1, 30));   // left of it
    EXPECT_TRUE(pyramid.isOccluded(0, 23, 36, 100));   // below it
    EXPECT_FALSE(pyramid.isOccluded(36, 22, 99, 99));  // one uncovered corner pixel
}

std::vector<glm::dvec2> randomTriangle(std::mt19937& rng, int w, int h, bool quantize) {
    std::uniform_real_distribution<double> unit(0.0, 1.0);
    const double size = std::pow(10.0, -0.5 + 3.0 * unit(rng));  // 0.3 .. 300 px
    const glm::dvec2 centre{-30.0 + unit(rng) * (w + 60.0), -30.0 + unit(rng) * (h + 60.0)};
    std::vector<glm::dvec2> v;
    for (int i = 0; i < 3; ++i) {
        glm::dvec2 p = centre + size * glm::dvec2(unit(rng) - 0.5, unit(rng) - 0.5);
        if (quantize) p = glm::round(p * 2.0) / 2.0;  // vertices on centres and corners
        v.push_back(p);
    }
    return v;
}

TEST(OcclusionPyramid, TopDownTrianglesMatchBottomUpScanConversion) {
    std::mt19937 rng(77);
    uint64_t triangles = 0;
    for (const auto& s : kSizes) {
        const int w = s[0], h = s[1];
        for (int run = 0; run < 4; ++run) {
            OcclusionPyramid topDown(w, h), bottomUp(w, h);
            const int count = run == 3 ? 300 : 60;  // the last run fills most of the image
            for (int t = 0; t < count; ++t) {
                const std::vector<glm::dvec2> v = randomTriangle(rng, w, h, t % 2 == 1);
                const glm::dvec2 tri[3] = {v[0], v[1], v[2]};
                const bool topDownChanged = topDown.insertTriangleTopDown(tri);
                const bool bottomUpChanged = scanConvertPolygon(v, bottomUp);
                EXPECT_EQ(topDownChanged, bottomUpChanged);
                bottomUp.propagate();
                ++triangles;
                for (int level = 0; level < topDown.levels(); ++level)
                    for (int wy = 0; wy < topDown.wordsY(level); ++wy)
                        for (int wx = 0; wx < topDown.wordsX(level); ++wx)
                            ASSERT_EQ(topDown.word(level, wx, wy), bottomUp.word(level, wx, wy))
                                << w << "x" << h << " triangle " << t << " level " << level
                                << " word " << wx << "," << wy << ": (" << v[0].x << ","
                                << v[0].y << ") (" << v[1].x << "," << v[1].y << ") ("
                                << v[2].x << "," << v[2].y << ")";
            }
            expectConsistentLevels(topDown);
        }
    }
    EXPECT_GT(triangles, 1000u);
}

TEST(OcclusionPyramid, TopDownFillsWholeNodesAtOnce) {
    OcclusionPyramid pyramid(512, 512);  // 3 levels
    const glm::dvec2 cover[3] = {{-10.0, -10.0}, {2000.0, -10.0}, {-10.0, 2000.0}};
    pyramid.insertTriangleTopDown(cover);
    expectConsistentLevels(pyramid);
    EXPECT_EQ(pyramid.word(2, 0, 0), ~uint64_t(0));
    EXPECT_TRUE(pyramid.isOccluded(0, 0, 511, 511));
    // Every word is written once, while filled subtrees are not classified pixel by pixel.
    EXPECT_LE(pyramid.stats().topDownWords, 1u + 64u + 4096u);
}

}  // namespace
}  // namespace vdiso
