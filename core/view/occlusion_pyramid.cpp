#include "core/view/occlusion_pyramid.h"

#include <algorithm>
#include <bit>
#include <cmath>
#include <stdexcept>

#include "core/view/edge_function.h"
#include "core/view/scan_convert.h"

namespace vdiso {

namespace {

constexpr uint64_t kFull = ~uint64_t(0);

// Bits of columns c0..c1 and rows r0..r1.
inline uint64_t rectMask(int c0, int c1, int r0, int r1) {
    return OcclusionPyramid::columnsMask(c0, c1) & OcclusionPyramid::rowsMask(r0, r1);
}

}  // namespace

OcclusionPyramid::OcclusionPyramid(int width, int height) : mWidth(width), mHeight(height) {
    if (width < 1 || height < 1)
        throw std::invalid_argument("OcclusionPyramid: image size must be positive");
    int gx = width, gy = height;  // size of the bit grid of the level being added
    size_t offset = 0;
    do {
        const int wx = (gx + kTileSize - 1) / kTileSize;
        const int wy = (gy + kTileSize - 1) / kTileSize;
        mWordsX.push_back(wx);
        mWordsY.push_back(wy);
        mLevelOffset.push_back(offset);
        offset += size_t(wx) * size_t(wy);
        gx = wx;
        gy = wy;
    } while (gx > 1 || gy > 1);

    // Bits beyond the image's edge count as covered: only the last column and row of words of
    // each level hold any (a whole tile's word starts at 0). A pyramid is made every frame.
    mClearWords.assign(offset, 0);
    for (int level = 0; level < levels(); ++level) {
        const int bitsX = level == 0 ? width : mWordsX[size_t(level) - 1];
        const int bitsY = level == 0 ? height : mWordsY[size_t(level) - 1];
        const int wordsX = mWordsX[size_t(level)], wordsY = mWordsY[size_t(level)];
        auto clear = [&](int wx, int wy) {
            const int cols = std::min(kTileSize, bitsX - wx * kTileSize);
            const int rows = std::min(kTileSize, bitsY - wy * kTileSize);
            mClearWords[mLevelOffset[size_t(level)] + size_t(wy) * size_t(wordsX) + size_t(wx)] =
                ~rectMask(0, cols - 1, 0, rows - 1);
        };
        for (int wy = 0; wy < wordsY; ++wy) clear(wordsX - 1, wy);
        for (int wx = 0; wx < wordsX; ++wx) clear(wx, wordsY - 1);
    }
    mWords = mClearWords;
    mTilesX = size_t(mWordsX[0]);
    mFewLevels = levels() <= 2;
}

void OcclusionPyramid::clear() {
    std::copy(mClearWords.begin(), mClearWords.end(), mWords.begin());
    mFilledTiles.clear();
}

// Beyond 2x2 tiles (isOccluded in the header answers those); the rectangle is clamped already.
bool OcclusionPyramid::isOccludedBeyond2x2(int x0, int y0, int x1, int y1) const {
    const int tx0 = x0 >> 3, tx1 = x1 >> 3, ty0 = y0 >> 3, ty1 = y1 >> 3;
    // Within 4x4 tiles (meta-cells' and small nodes' boxes): the bottom words row by row, up to
    // the first with an uncovered pixel of the rectangle. From the top such a query read four
    // levels and cost about 550 instructions (cachegrind, ch2better's normal view).
    if (tx1 - tx0 <= 3 && ty1 - ty0 <= 3 && levels() > 2) {
        const size_t stride = size_t(mWordsX[0]);
        for (int ty = ty0; ty <= ty1; ++ty) {
            const uint64_t rows = rowsMask(ty == ty0 ? y0 & 7 : 0, ty == ty1 ? y1 & 7 : 7);
            const uint64_t* w = mWords.data() + size_t(ty) * stride;
            for (int tx = tx0; tx <= tx1; ++tx) {
                ++mStats.queryWords;
                if (rows & columnsMask(tx == tx0 ? x0 & 7 : 0, tx == tx1 ? x1 & 7 : 7) & ~w[tx]) return false;
            }
        }
        return true;
    }
    // From the lowest level one of whose words holds the whole rectangle: the levels above
    // would each read a word only to come down to it.
    int level = std::min(1, levels() - 1);
    while (level < levels() - 1 &&
           ((x0 ^ x1) >> (3 * level + 3) != 0 || (y0 ^ y1) >> (3 * level + 3) != 0))
        ++level;
    return queryWord(level, x0 >> (3 * level + 3), y0 >> (3 * level + 3), x0, y0, x1, y1);
}

// [x0, x1] x [y0, y1] lies in the image and in the region of word (wx, wy) of the level.
bool OcclusionPyramid::queryWord(int level, int wx, int wy, int x0, int y0, int x1,
                                 int y1) const {
    ++mStats.queryWords;
    const int shift = 3 * level;  // a bit of this level covers 2^shift pixels each way
    const int baseX = wx * kTileSize, baseY = wy * kTileSize;
    const uint64_t mask = rectMask((x0 >> shift) - baseX, (x1 >> shift) - baseX,
                                   (y0 >> shift) - baseY, (y1 >> shift) - baseY);
    uint64_t missing = mask & ~word(level, wx, wy);
    if (missing == 0) return true;
    if (level == 0) return false;

    // An unfilled cell lying wholly inside the rectangle has an uncovered pixel in it: answer
    // without descending. Cells only partly inside need a look below.
    const int cellLast = (1 << shift) - 1;
    for (uint64_t m = missing; m != 0; m &= m - 1) {
        const int bit = std::countr_zero(m);
        const int cx0 = (baseX + (bit & 7)) << shift, cy0 = (baseY + (bit >> 3)) << shift;
        const int cx1 = std::min(cx0 + cellLast, mWidth - 1);
        const int cy1 = std::min(cy0 + cellLast, mHeight - 1);
        if (x0 <= cx0 && cx1 <= x1 && y0 <= cy0 && cy1 <= y1) return false;
    }
    for (; missing != 0; missing &= missing - 1) {
        const int bit = std::countr_zero(missing);
        const int cx = baseX + (bit & 7), cy = baseY + (bit >> 3);
        const int cx0 = cx << shift, cy0 = cy << shift;
        if (!queryWord(level - 1, cx, cy, std::max(x0, cx0), std::max(y0, cy0),
                       std::min(x1, cx0 + cellLast), std::min(y1, cy0 + cellLast)))
            return false;
    }
    return true;
}

bool OcclusionPyramid::coverSpan(int y, int x0, int x1) {
    if (y < 0 || y >= mHeight) return false;
    x0 = std::max(x0, 0);
    x1 = std::min(x1, mWidth - 1);
    if (x0 > x1) return false;
    ++mStats.spans;
    bool changed = false;
    const int rowShift = (y & 7) * 8;
    for (int tx = x0 >> 3, last = x1 >> 3; tx <= last; ++tx) {
        const int c0 = std::max(x0 - tx * kTileSize, 0);
        const int c1 = std::min(x1 - tx * kTileSize, kTileSize - 1);
        const uint64_t m = ((uint64_t(0xFF) >> (7 - (c1 - c0))) << c0) << rowShift;
        changed |= coverTile(tx, y >> 3, m);
    }
    return changed;
}

bool OcclusionPyramid::coverTiles(std::span<const uint64_t> tiles) {
    if (tiles.size() != this->tiles().size())
        throw std::invalid_argument("OcclusionPyramid::coverTiles: tiles of another image size");
    bool changed = false;
    const size_t tilesX = size_t(mWordsX[0]);
    for (size_t t = 0; t < tiles.size(); ++t) changed |= coverTile(int(t % tilesX), int(t / tilesX), tiles[t]);
    return changed;
}

void OcclusionPyramid::propagate() {
    const uint32_t tilesX = uint32_t(mWordsX[0]);
    for (const uint32_t tile : mFilledTiles) {
        int wx = int(tile % tilesX), wy = int(tile / tilesX);
        for (int level = 1; level < levels(); ++level) {
            uint64_t& parent = wordRef(level, wx >> 3, wy >> 3);
            const uint64_t before = parent;
            parent |= uint64_t(1) << ((wy & 7) * 8 + (wx & 7));
            ++mStats.propagatedWords;
            if (parent == before || parent != kFull) break;
            wx >>= 3;
            wy >>= 3;
        }
    }
    mFilledTiles.clear();
}

// --- WISE: top-down insertion of one triangle ------------------------------------------------

struct OcclusionPyramid::TopDownTriangle {
    detail::ScanEdge edges[3];
    int edgeCount = 0;
    // Edge half-planes a*x + b*y + c, scaled to distances, positive inside.
    double a[3], b[3], c[3];
    bool canBeInside = false;  // false for a degenerate triangle: only the scan rows decide
    double margin = 0.0;
    int colBegin = 0, colEnd = -1, rowBegin = 0, rowEnd = -1;  // inclusive pixel bounds

    // -1: every centre of the pixel rectangle outside, +1: every centre inside, 0: undecided.
    // The margin leaves centres near an edge to the bottom level, where the scan converter's
    // own arithmetic decides, so both methods agree exactly.
    int classify(int x0, int y0, int x1, int y1) const {
        const double px0 = x0 + 0.5, px1 = x1 + 0.5, py0 = y0 + 0.5, py1 = y1 + 0.5;
        bool inside = canBeInside;
        for (int e = 0; e < 3; ++e) {
            const double lo = c[e] + std::min(a[e] * px0, a[e] * px1) +
                              std::min(b[e] * py0, b[e] * py1);
            const double hi = c[e] + std::max(a[e] * px0, a[e] * px1) +
                              std::max(b[e] * py0, b[e] * py1);
            if (hi < -margin) return -1;
            if (!(lo > margin)) inside = false;
        }
        return inside ? 1 : 0;
    }
};

bool OcclusionPyramid::insertTriangleTopDown(const glm::dvec2 (&v)[3]) {
    ++mStats.topDownTriangles;
    TopDownTriangle t;
    double yMin, yMax;
    t.edgeCount = detail::buildScanEdges(v, 3, t.edges, yMin, yMax);
    if (t.edgeCount < 2) return false;  // not finite, or flat: the scan converter covers nothing

    const TriangleEdgeFunctions f = TriangleEdgeFunctions::of(v[0], v[1], v[2]);
    t.canBeInside = !f.degenerate;
    double extent = std::max(mWidth, mHeight);
    for (int e = 0; e < 3; ++e) {
        t.a[e] = f.a[e];
        t.b[e] = f.b[e];
        t.c[e] = f.c[e];
        extent = std::max({extent, std::abs(v[e].x), std::abs(v[e].y)});
    }
    // Far above the rounding of both the edge functions and the scan converter's crossings.
    t.margin = 1e-9 * (1.0 + extent);

    const double xMin = std::min({v[0].x, v[1].x, v[2].x});
    const double xMax = std::max({v[0].x, v[1].x, v[2].x});
    // A pixel or so of slack: the bounds only prune, the edges and the rows decide.
    t.colBegin = std::max(detail::firstCentreAtOrAfter(xMin, mWidth) - 1, 0);
    t.colEnd = std::min(detail::firstCentreAtOrAfter(xMax, mWidth) + 1, mWidth - 1);
    t.rowBegin = std::max(detail::firstCentreAtOrAfter(yMin, mHeight) - 1, 0);
    t.rowEnd = std::min(detail::firstCentreAtOrAfter(yMax, mHeight) + 1, mHeight - 1);
    if (t.colBegin > t.colEnd || t.rowBegin > t.rowEnd) return false;
    mTopDownChanged = false;
    insertWord(t, levels() - 1, 0, 0);
    return mTopDownChanged;
}

// Inserts the triangle into word (wx, wy) of the level; returns whether the word is full.
bool OcclusionPyramid::insertWord(const TopDownTriangle& t, int level, int wx, int wy) {
    ++mStats.topDownWords;
    uint64_t& w = wordRef(level, wx, wy);
    const int baseX = wx * kTileSize, baseY = wy * kTileSize;
    if (level == 0) {
        detail::ScanCrossing scratch[3];
        int rowShift = 0;
        auto sink = [&](int, int x0, int x1) {
            x0 = std::max(x0, baseX);
            x1 = std::min(x1, baseX + kTileSize - 1);
            if (x0 <= x1) w |= rectMask(x0 - baseX, x1 - baseX, 0, 0) << (rowShift * 8);
        };
        const int rowFirst = std::max(t.rowBegin, baseY);
        const int rowLast = std::min(t.rowEnd, baseY + kTileSize - 1);
        const uint64_t before = w;
        for (int row = rowFirst; row <= rowLast; ++row) {
            rowShift = row - baseY;
            detail::scanRow(t.edges, t.edgeCount, scratch, row, mWidth, sink);
        }
        mTopDownChanged |= w != before;
        return w == kFull;
    }

    const int shift = 3 * level;
    const int cellLast = (1 << shift) - 1;
    const int cxFirst = std::max(t.colBegin >> shift, baseX);
    const int cxLast = std::min({t.colEnd >> shift, baseX + kTileSize - 1,
                                 mWordsX[size_t(level) - 1] - 1});
    const int cyFirst = std::max(t.rowBegin >> shift, baseY);
    const int cyLast = std::min({t.rowEnd >> shift, baseY + kTileSize - 1,
                                 mWordsY[size_t(level) - 1] - 1});
    for (int cy = cyFirst; cy <= cyLast; ++cy) {
        for (int cx = cxFirst; cx <= cxLast; ++cx) {
            const uint64_t bit = uint64_t(1) << ((cy - baseY) * 8 + (cx - baseX));
            if (w & bit) continue;
            const int x0 = cx << shift, y0 = cy << shift;
            const int cls = t.classify(x0, y0, std::min(x0 + cellLast, mWidth - 1),
                                       std::min(y0 + cellLast, mHeight - 1));
            if (cls < 0) continue;
            if (cls > 0) {
                fillSubtree(level - 1, cx, cy);
                w |= bit;
            } else if (insertWord(t, level - 1, cx, cy)) {
                w |= bit;
            }
        }
    }
    return w == kFull;
}

void OcclusionPyramid::fillSubtree(int level, int wx, int wy) {
    ++mStats.topDownWords;
    uint64_t& w = wordRef(level, wx, wy);
    mTopDownChanged |= w != kFull;
    w = kFull;
    if (level == 0) return;
    const int xEnd = std::min((wx + 1) * kTileSize, mWordsX[size_t(level) - 1]);
    const int yEnd = std::min((wy + 1) * kTileSize, mWordsY[size_t(level) - 1]);
    for (int cy = wy * kTileSize; cy < yEnd; ++cy)
        for (int cx = wx * kTileSize; cx < xEnd; ++cx) fillSubtree(level - 1, cx, cy);
}

}  // namespace vdiso
