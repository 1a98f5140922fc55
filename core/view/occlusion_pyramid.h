// The occlusion pyramid: which pixels of the image are already covered by extracted surface
// (SAGE §3.1, Fig. 1; after Greene's hierarchical coverage masks as used by WISE).
//
// Coverage only, no depth: the traversal delivers geometry front to back, so anything drawn
// later lies behind what is already covered. Pixels follow core/camera.h (x right, y down).
//
// Layout: level 0 holds one bit per pixel in 8x8 tiles, one uint64_t per tile
// (bit = row * 8 + column). Level k + 1 holds one "full" bit per word of level k, again grouped
// 8x8 into words, up to a single word at the top (levels() of them; a bit of level k stands for
// 8^k x 8^k pixels). Bits outside the image (the ragged right and bottom tiles, and bits of
// level k + 1 for words that level k does not have) are kept set, so that "full" is simply
// word == ~0 and a tile on the image border can become full.
//
// Update bottom-up (SAGE): coverSpan() sets pixel bits with word masks and remembers the tiles
// that became full; propagate() carries just those up. Queries (isOccluded) go top-down with
// early exit and are valid after propagate(). The WISE alternative, insertTriangleTopDown(),
// descends from the top classifying nodes against the triangle's edges and keeps the full bits
// consistent itself; it covers exactly the pixels scanConvertPolygon() (core/view/scan_convert.h)
// covers for the same triangle.
//
// Memory: about width * height / 8 * (1 + 1/64 + ...) bytes. Not thread-safe, not even for
// concurrent queries (they count the words they touch): one pyramid per extraction.
#pragma once

#include <algorithm>
#include <cstdint>
#include <span>
#include <vector>

#include <glm/vec2.hpp>

namespace vdiso {

namespace detail {
// The bits of columns, and of rows, first..last of an 8x8 word.
struct WordMasks {
    uint64_t columns[64], rows[64];  // [first * 8 + last], first <= last
    constexpr WordMasks() : columns(), rows() {
        for (int a = 0; a < 8; ++a)
            for (int b = a; b < 8; ++b) {
                columns[a * 8 + b] = ((uint64_t(0xFF) >> (7 - (b - a))) << a) * 0x0101010101010101ull;
                rows[a * 8 + b] = (~uint64_t(0) >> ((7 - b) * 8)) & (~uint64_t(0) << (a * 8));
            }
    }
};
inline constexpr WordMasks kWordMasks{};
}  // namespace detail

class OcclusionPyramid {
public:
    static constexpr int kTileSize = 8;

    struct Stats {
        uint64_t spans = 0;          // coverSpan calls that touched the image
        uint64_t tileUpdates = 0;    // bottom words changed by spans (a word may count often)
        uint64_t tilesFilled = 0;    // bottom words that became full through spans
        uint64_t propagatedWords = 0;  // words above the bottom written by propagate()
        uint64_t queryWords = 0;     // words read by isOccluded beyond 2x2 tiles
        uint64_t topDownTriangles = 0;
        uint64_t topDownWords = 0;   // words visited by insertTriangleTopDown
    };

    OcclusionPyramid(int width, int height);  // width, height >= 1

    // Uncovers every pixel (keeps the sizes and the statistics).
    void clear();

    int width() const { return mWidth; }
    int height() const { return mHeight; }
    int levels() const { return int(mWordsX.size()); }

    // (x, y) must lie in the image.
    bool isCovered(int x, int y) const {
        const uint64_t w = mWords[size_t(y >> 3) * mWordsX[0] + (x >> 3)];
        return (w >> ((y & 7) * 8 + (x & 7))) & 1;
    }

    // True when every pixel of the inclusive rectangle [x0, x1] x [y0, y1], clamped to the
    // image, is covered; true as well when nothing of it is left after clamping (no pixel of
    // it can be seen). Needs propagate() after the last coverSpan() for rectangles beyond 4x4
    // tiles; smaller ones are answered from the bottom words.
    // Inline for a rectangle within 2x2 tiles (the per-cell and per-polygon queries, most of
    // them): the four words read directly, its columns in the left and right tile and its rows
    // in the top and bottom one as masks made once. (Not counted in the statistics: it was a
    // tenth of a query's instructions.)
    [[gnu::always_inline]] bool isOccluded(int x0, int y0, int x1, int y1) const {
        x0 = std::max(x0, 0);
        y0 = std::max(y0, 0);
        x1 = std::min(x1, mWidth - 1);
        y1 = std::min(y1, mHeight - 1);
        if (x0 > x1 || y0 > y1) return true;
        const int tx0 = x0 >> 3, tx1 = x1 >> 3, ty0 = y0 >> 3, ty1 = y1 >> 3;
        // (With two levels or fewer the top-down walk reads as few words.)
        if (tx1 - tx0 > 1 || ty1 - ty0 > 1 || (mFewLevels && ((tx0 ^ tx1) | (ty0 ^ ty1)) != 0))
            return isOccludedBeyond2x2(x0, y0, x1, y1);
        // One to four words, without a branch on how many: whether the rectangle crosses into a
        // second tile column or row is as likely as not, and its branches mispredicted. A word
        // not crossed into is read again in the first's place and asked for no bits.
        const int twoX = tx1 - tx0, twoY = ty1 - ty0;  // 0 or 1
        const size_t down = size_t(twoY) * mTilesX;
        const uint64_t* w = mWords.data() + size_t(ty0) * mTilesX + size_t(tx0);
        const uint64_t left = columnsMask(x0 & 7, (x1 & 7) | (7 * twoX));
        const uint64_t right = columnsMask(0, x1 & 7) & (uint64_t(0) - uint64_t(twoX));
        const uint64_t top = rowsMask(y0 & 7, (y1 & 7) | (7 * twoY));
        const uint64_t bottom = rowsMask(0, y1 & 7) & (uint64_t(0) - uint64_t(twoY));
        const uint64_t missing = (left & top & ~w[0]) | (right & top & ~w[twoX]) | (left & bottom & ~w[down]) |
                                 (right & bottom & ~w[down + size_t(twoX)]);
        return missing == 0;
    }

    // Calls found(x, y) for the pixels of [x0, x1] x [y0, y1] (within the image) not covered,
    // a tile at a time, until it returns true; whether it did. Covered pixels cost nothing.
    template <class Found>
    bool findUncovered(int x0, int y0, int x1, int y1, Found&& found) const {
        for (int ty = y0 >> 3; ty <= y1 >> 3; ++ty) {
            const uint64_t rows = rowsMask(std::max(y0 - ty * 8, 0), std::min(y1 - ty * 8, 7));
            for (int tx = x0 >> 3; tx <= x1 >> 3; ++tx) {
                uint64_t open = ~tileWord(tx, ty) & rows & columnsMask(std::max(x0 - tx * 8, 0), std::min(x1 - tx * 8, 7));
                for (; open != 0; open &= open - 1) {
                    const int bit = __builtin_ctzll(open);
                    if (found(tx * 8 + (bit & 7), ty * 8 + (bit >> 3))) return true;
                }
            }
        }
        return false;
    }

    // Bits of columns c0..c1 of every row of an 8x8 word, and of every column of rows r0..r1
    // (inclusive, 0..7, c0 <= c1, r0 <= r1).
    // By table (two of 64 words): made by shifts they were a third of a one-tile query.
    static uint64_t columnsMask(int c0, int c1) { return detail::kWordMasks.columns[c0 * 8 + c1]; }
    static uint64_t rowsMask(int r0, int r1) { return detail::kWordMasks.rows[r0 * 8 + r1]; }

    // Covers pixels x0..x1 (inclusive, clamped to the image) of row y; returns whether any of
    // them was not covered before.
    bool coverSpan(int y, int x0, int x1);
    // The bottom word of tile (tx, ty) (bit = row * 8 + column); both in the image's tiles.
    uint64_t tileWord(int tx, int ty) const { return mWords[size_t(ty) * mWordsX[0] + size_t(tx)]; }
    // Covers the pixels set in `mask` of tile (tx, ty); returns whether any was not covered
    // before.
    bool coverTile(int tx, int ty, uint64_t mask) {
        const size_t at = size_t(ty) * mWordsX[0] + size_t(tx);
        uint64_t& w = mWords[at];
        if ((w | mask) == w) return false;
        w |= mask;
        ++mStats.tileUpdates;
        // Coverage only grows, so the one change that matters above is a tile becoming full,
        // and that happens once per tile: no duplicates in the list.
        if (w == ~uint64_t(0)) {
            ++mStats.tilesFilled;
            mFilledTiles.push_back(uint32_t(at));
        }
        return true;
    }
    // Carries the tiles filled since the last call up the hierarchy.
    void propagate();
    bool hasPendingChanges() const { return !mFilledTiles.empty(); }

    // The bottom level as it stands: one word per 8x8 tile, rows of wordsX(0) tiles, bits outside
    // the image set. One process's coverage as exchanged with others (mpi/): width * height / 8
    // bytes, 128 KB for 1024 x 1024.
    std::span<const uint64_t> tiles() const { return {mWords.data(), tileCount(mWidth, mHeight)}; }
    static size_t tileCount(int width, int height) {
        return size_t((width + kTileSize - 1) / kTileSize) * size_t((height + kTileSize - 1) / kTileSize);
    }
    // Covers the pixels set in `tiles` (laid out as tiles() of a pyramid of the same size); then
    // propagate(). Returns whether any was not covered before.
    bool coverTiles(std::span<const uint64_t> tiles);

    // WISE (Greene): covers the pixel centres inside the triangle (the fill and tie rules of
    // core/view/scan_convert.h) by descending from the top word; whole nodes inside the triangle are
    // filled at once. Keeps every level consistent; unrelated pending coverSpan() changes still
    // need propagate(). Returns whether any pixel was not covered before.
    bool insertTriangleTopDown(const glm::dvec2 (&v)[3]);

    // Inspection (tests, debugging): word (wx, wy) of a level, and the size of its word grid.
    int wordsX(int level) const { return mWordsX[size_t(level)]; }
    int wordsY(int level) const { return mWordsY[size_t(level)]; }
    uint64_t word(int level, int wx, int wy) const {
        return mWords[mLevelOffset[size_t(level)] + size_t(wy) * mWordsX[size_t(level)] +
                      size_t(wx)];
    }

    const Stats& stats() const { return mStats; }
    void resetStats() { mStats = Stats{}; }

private:
    struct TopDownTriangle;

    uint64_t& wordRef(int level, int wx, int wy) {
        return mWords[mLevelOffset[size_t(level)] + size_t(wy) * mWordsX[size_t(level)] +
                      size_t(wx)];
    }
    bool isOccludedBeyond2x2(int x0, int y0, int x1, int y1) const;
    bool queryWord(int level, int wx, int wy, int x0, int y0, int x1, int y1) const;
    bool insertWord(const TopDownTriangle& t, int level, int wx, int wy);
    void fillSubtree(int level, int wx, int wy);
    bool mTopDownChanged = false;  // set by insertWord/fillSubtree during one insertion

    int mWidth, mHeight;
    size_t mTilesX;    // words a row of the bottom level
    bool mFewLevels;   // two levels or fewer
    std::vector<int> mWordsX, mWordsY;   // word grid per level
    std::vector<size_t> mLevelOffset;    // first word of each level in mWords
    std::vector<uint64_t> mWords;        // all levels, bottom first, rows of words
    std::vector<uint64_t> mClearWords;   // mWords after clear(): only the padding bits set
    std::vector<uint32_t> mFilledTiles;  // bottom words filled since the last propagate()
    mutable Stats mStats;
};

}  // namespace vdiso
