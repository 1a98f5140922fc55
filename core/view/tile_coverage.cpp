#include "core/view/tile_coverage.h"

#include <algorithm>
#include <bit>
#include <cmath>

#if VDISO_HAS_AVX2_PATHS
#include <immintrin.h>
#endif

namespace vdiso {

namespace {

constexpr uint64_t kByteOnes = 0x0101010101010101ull;  // 1 in each byte
constexpr uint64_t kByteZero = 0x8080808080808080ull;  // winding 0 in each byte, offset by 128
constexpr uint64_t kFull = ~uint64_t(0);

// What one tile row [row0, row1] (image rows, within tile row ty) of a polygon needs.
struct TileRow {
    const detail::ScanEdge* edges;
    int edgeCount;
    int ty, row0, row1;
    int tileX0, tileX1;
    int width;
};

// Bit j set where byte j of `bytes` is not zero.
inline uint64_t nonzeroBytes(uint64_t bytes) {
    uint64_t t = bytes | bytes >> 4;
    t |= t >> 2;
    t |= t >> 1;
    return ((t & kByteOnes) * 0x0102040810204080ull) >> 56;
}

// The baseline: each row's crossings listed, then per tile a word of byte counters per row.
bool coverTileRowBaseline(const TileRow& t, OcclusionPyramid& pyramid) {
    int column[8][kTileCoverageEdges];  // the first centre at or after the crossing
    int winding[8][kTileCoverageEdges];
    int crossings[8];
    for (int row = t.row0; row <= t.row1; ++row) {
        const double yc = row + 0.5;
        const int k = row - t.row0;
        int count = 0;
        for (int e = 0; e < t.edgeCount; ++e) {
            const detail::ScanEdge& edge = t.edges[e];
            if (!(edge.yTop <= yc && yc < edge.yBottom)) continue;
            // scanRow's crossing, to the bit.
            const double x = edge.xTop + (yc - edge.yTop) * edge.dx / edge.dy;
            column[k][count] = detail::firstCentreAtOrAfter(x, t.width);
            winding[k][count] = edge.winding;
            ++count;
        }
        crossings[k] = count;
    }
    bool fresh = false;
    for (int tx = t.tileX0; tx <= t.tileX1; ++tx) {
        const uint64_t word = pyramid.tileWord(tx, t.ty);
        if (word == kFull) continue;
        uint64_t mask = 0;
        for (int row = t.row0; row <= t.row1; ++row) {
            const int k = row - t.row0;
            uint64_t counters = kByteZero;
            for (int c = 0; c < crossings[k]; ++c) {
                const int at = column[k][c] - tx * 8;
                if (at >= 8) continue;
                const uint64_t step = at <= 0 ? kByteOnes : kByteOnes << (8 * at);
                counters = winding[k][c] > 0 ? counters + step : counters - step;
            }
            mask |= nonzeroBytes(counters ^ kByteZero) << (8 * (row & 7));
        }
        if (mask & ~word) fresh |= pyramid.coverTile(tx, t.ty, mask);
    }
    return fresh;
}

#if VDISO_HAS_AVX2_PATHS
// detail::firstCentreAtOrAfter of four lanes (clamped to [-1, hi]), as int32 lanes.
VDISO_TARGET_AVX2 inline __m128i firstCentresAtOrAfter(__m256d x, __m256d hi) {
    const __m256d clamped = _mm256_min_pd(_mm256_max_pd(x, _mm256_set1_pd(-1.0)), hi);
    return _mm256_cvtpd_epi32(_mm256_round_pd(_mm256_sub_pd(clamped, _mm256_set1_pd(0.5)), _MM_FROUND_TO_POS_INF | _MM_FROUND_NO_EXC));
}

// AVX2: a quad of rows (tile rows 0-3 or 4-7) at a time. Per edge, the quad's four crossings in
// one register (the same operations in the same order as the baseline's, so the same bits:
// IEEE division, and vroundpd's ceiling is exact), kept as the column of the first centre at or
// after each, or a far column where the edge misses the row. Per tile, a row's eight byte
// counters are one 64-bit lane: each edge adds its step to the four rows at once, the step made
// by a variable shift (zero once the shift passes 63: the crossing lies right of the tile), and
// the counters that are not zero are the tile's bits, in the tile's own layout, by one
// byte-compare and movemask.
VDISO_TARGET_AVX2 bool coverTileRowAvx2(const TileRow& t, OcclusionPyramid& pyramid) {
    const int quad0 = (t.row0 & 7) >> 2, quad1 = (t.row1 & 7) >> 2;
    __m256i column[2][kTileCoverageEdges];
    int winding[2][kTileCoverageEdges];
    int used[2] = {0, 0};
    const __m256d hi = _mm256_set1_pd(double(t.width) + 1.0);
    const __m256i far = _mm256_set1_epi64x(int64_t(1) << 40);
    for (int q = quad0; q <= quad1; ++q) {
        const double firstCentre = t.ty * 8 + q * 4 + 0.5;
        const __m256d yc = _mm256_add_pd(_mm256_set1_pd(firstCentre), _mm256_set_pd(3.0, 2.0, 1.0, 0.0));
        for (int e = 0; e < t.edgeCount; ++e) {
            const detail::ScanEdge& edge = t.edges[e];
            if (edge.yBottom <= firstCentre || edge.yTop > firstCentre + 3.0) continue;  // misses the quad
            const __m256d yTop = _mm256_set1_pd(edge.yTop);
            const __m256d active = _mm256_and_pd(_mm256_cmp_pd(yTop, yc, _CMP_LE_OQ),
                                                 _mm256_cmp_pd(yc, _mm256_set1_pd(edge.yBottom), _CMP_LT_OQ));
            const __m256d x = _mm256_add_pd(
                _mm256_set1_pd(edge.xTop),
                _mm256_div_pd(_mm256_mul_pd(_mm256_sub_pd(yc, yTop), _mm256_set1_pd(edge.dx)), _mm256_set1_pd(edge.dy)));
            const __m256i at = _mm256_cvtepi32_epi64(firstCentresAtOrAfter(x, hi));
            column[q][used[q]] = _mm256_blendv_epi8(far, at, _mm256_castpd_si256(active));
            winding[q][used[q]] = edge.winding;
            ++used[q];
        }
    }
    const __m256i ones = _mm256_set1_epi8(1), zero = _mm256_set1_epi8(char(0x80));
    bool fresh = false;
    for (int tx = t.tileX0; tx <= t.tileX1; ++tx) {
        const uint64_t word = pyramid.tileWord(tx, t.ty);
        if (word == kFull) continue;
        const __m256i tileColumn = _mm256_set1_epi64x(int64_t(tx) * 8);
        uint64_t mask = 0;
        for (int q = quad0; q <= quad1; ++q) {
            __m256i counters = zero;
            for (int c = 0; c < used[q]; ++c) {
                __m256i at = _mm256_sub_epi64(column[q][c], tileColumn);
                at = _mm256_and_si256(at, _mm256_cmpgt_epi64(at, _mm256_setzero_si256()));  // at <= 0: every byte
                const __m256i step = _mm256_sllv_epi64(ones, _mm256_slli_epi64(at, 3));
                counters = winding[q][c] > 0 ? _mm256_add_epi8(counters, step) : _mm256_sub_epi8(counters, step);
            }
            const uint32_t windingZero = uint32_t(_mm256_movemask_epi8(_mm256_cmpeq_epi8(counters, zero)));
            mask |= uint64_t(~windingZero) << (32 * q);
        }
        if (mask & ~word) fresh |= pyramid.coverTile(tx, t.ty, mask);
    }
    return fresh;
}
#endif

#if VDISO_HAS_AVX2_PATHS
// AVX2, a tile row's eight rows at once, for a tile row where no row crosses more than two edges
// (every row of a convex outline, most of a marching-cubes polygon's): per edge, the eight
// rows' crossings in two registers (scanRow's operations in its order: the same bits), kept as
// the least and the greatest active crossing of each row. A row crossing two edges covers the
// centres from the first at or after the one to the last before the other (scanRow's single
// run: the crossings wind opposite ways); a row crossing none covers nothing. Per tile, each
// row's byte is then two shifts of 0xFF, the eight bytes packed into the tile's word: no work
// per crossing and tile. Returns false, covering nothing, when a row of [row0, row1] crosses
// more than two edges (the caller takes coverTileRowAvx2 for that tile row).
VDISO_TARGET_AVX2 bool coverTileRowSpansAvx2(const TileRow& t, OcclusionPyramid& pyramid, bool& fresh) {
    const double firstCentre = t.ty * 8 + 0.5;
    const __m256d ycLo = _mm256_add_pd(_mm256_set1_pd(firstCentre), _mm256_set_pd(3.0, 2.0, 1.0, 0.0));
    const __m256d ycHi = _mm256_add_pd(ycLo, _mm256_set1_pd(4.0));
    const __m256d inf = _mm256_set1_pd(INFINITY), minusInf = _mm256_set1_pd(-INFINITY);
    __m256d leastLo = inf, leastHi = inf, mostLo = minusInf, mostHi = minusInf;
    __m256i countLo = _mm256_setzero_si256(), countHi = _mm256_setzero_si256();  // minus the edges crossed
    for (int e = 0; e < t.edgeCount; ++e) {
        const detail::ScanEdge& edge = t.edges[e];
        if (edge.yBottom <= firstCentre || edge.yTop > firstCentre + 7.0) continue;  // misses the tile row
        const __m256d yTop = _mm256_set1_pd(edge.yTop), yBottom = _mm256_set1_pd(edge.yBottom);
        const __m256d xTop = _mm256_set1_pd(edge.xTop), dx = _mm256_set1_pd(edge.dx), dy = _mm256_set1_pd(edge.dy);
        const __m256d activeLo = _mm256_and_pd(_mm256_cmp_pd(yTop, ycLo, _CMP_LE_OQ), _mm256_cmp_pd(ycLo, yBottom, _CMP_LT_OQ));
        const __m256d activeHi = _mm256_and_pd(_mm256_cmp_pd(yTop, ycHi, _CMP_LE_OQ), _mm256_cmp_pd(ycHi, yBottom, _CMP_LT_OQ));
        const __m256d xLo = _mm256_add_pd(xTop, _mm256_div_pd(_mm256_mul_pd(_mm256_sub_pd(ycLo, yTop), dx), dy));
        const __m256d xHi = _mm256_add_pd(xTop, _mm256_div_pd(_mm256_mul_pd(_mm256_sub_pd(ycHi, yTop), dx), dy));
        // An inactive lane's quotient may be inf or NaN: it never reaches the least or most.
        leastLo = _mm256_min_pd(leastLo, _mm256_blendv_pd(inf, xLo, activeLo));
        leastHi = _mm256_min_pd(leastHi, _mm256_blendv_pd(inf, xHi, activeHi));
        mostLo = _mm256_max_pd(mostLo, _mm256_blendv_pd(minusInf, xLo, activeLo));
        mostHi = _mm256_max_pd(mostHi, _mm256_blendv_pd(minusInf, xHi, activeHi));
        countLo = _mm256_add_epi64(countLo, _mm256_castpd_si256(activeLo));
        countHi = _mm256_add_epi64(countHi, _mm256_castpd_si256(activeHi));
    }
    // Rows of [row0, row1] crossing more than two edges (count below -2).
    const __m256i minusTwo = _mm256_set1_epi64x(-2);
    const uint32_t many = uint32_t(_mm256_movemask_pd(_mm256_castsi256_pd(_mm256_cmpgt_epi64(minusTwo, countLo)))) |
                          uint32_t(_mm256_movemask_pd(_mm256_castsi256_pd(_mm256_cmpgt_epi64(minusTwo, countHi)))) << 4;
    const uint32_t rows = (0xFFu >> (7 - (t.row1 & 7))) & (0xFFu << (t.row0 & 7));
    if (many & rows) return false;
    // firstCentreAtOrAfter of each row's least and greatest crossing (a row crossing nothing:
    // the width plus one and -1, an empty run), as eight int32 lanes, rows 0..7.
    const __m256d hi = _mm256_set1_pd(double(t.width) + 1.0);
    const __m256i first = _mm256_setr_m128i(firstCentresAtOrAfter(leastLo, hi), firstCentresAtOrAfter(leastHi, hi));
    const __m256i last = _mm256_sub_epi32(_mm256_setr_m128i(firstCentresAtOrAfter(mostLo, hi), firstCentresAtOrAfter(mostHi, hi)),
                                          _mm256_set1_epi32(1));
    const __m256i bytes = _mm256_set1_epi32(0xFF), seven = _mm256_set1_epi32(7);
    // Byte 0 of each int32 lane, gathered into the low eight bytes.
    const __m256i gather = _mm256_setr_epi8(0, 4, 8, 12, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1,
                                            0, 4, 8, 12, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1);
    const __m256i halves = _mm256_setr_epi32(0, 4, 1, 1, 1, 1, 1, 1);
    const uint64_t rowBits = OcclusionPyramid::rowsMask(t.row0 & 7, t.row1 & 7);
    for (int tx = t.tileX0; tx <= t.tileX1; ++tx) {
        const uint64_t word = pyramid.tileWord(tx, t.ty);
        if (word == kFull) continue;
        const __m256i column = _mm256_set1_epi32(tx * 8);
        // Columns [from, to] of the tile in each row: 0xFF << from & 0xFF >> (7 - to), empty when
        // from > to (shifts of 32 or more give 0).
        const __m256i from = _mm256_max_epi32(_mm256_sub_epi32(first, column), _mm256_setzero_si256());
        const __m256i to = _mm256_min_epi32(_mm256_sub_epi32(last, column), seven);
        const __m256i row = _mm256_and_si256(_mm256_sllv_epi32(bytes, from), _mm256_srlv_epi32(bytes, _mm256_sub_epi32(seven, to)));
        const __m256i packed = _mm256_permutevar8x32_epi32(_mm256_shuffle_epi8(row, gather), halves);
        const uint64_t mask = uint64_t(_mm_cvtsi128_si64(_mm256_castsi256_si128(packed))) & rowBits;
        if (mask & ~word) fresh |= pyramid.coverTile(tx, t.ty, mask);
    }
    return true;
}
#endif

// A polygon whose centres lie in one or two rows of one tile (most of them, where cells are a
// pixel or two; taller ones go four rows at a time in the paths above): each row's crossings made straight from the outline, every edge every row, with no branch on the
// data. The rows' rules and arithmetic are scanRow's (an edge counts for a row when
// yTop <= yc < yBottom, its crossing xTop + (yc - yTop) * dx / dy from its upper end) and the
// winding counters the baseline's, so the bits are the same; for such polygons the branches
// that sort edges and crossings mispredicted more than the arithmetic cost.
bool coverPolygonInTile(const glm::dvec2* v, int n, const PixelRect& rect, OcclusionPyramid& pyramid) {
    const int tx = rect.x0 >> 3, ty = rect.y0 >> 3;
    const uint64_t word = pyramid.tileWord(tx, ty);
    if (word == kFull) return false;
    int finite = 1;  // ints, not bools: no branch per vertex
    for (int k = 0; k < n; ++k) finite &= int(std::isfinite(v[k].x)) & int(std::isfinite(v[k].y));
    if (!finite) return false;  // as buildScanEdges: such a polygon covers nothing
    const int width = pyramid.width(), column0 = tx * 8;
    uint64_t mask = 0;
    for (int row = rect.y0; row <= rect.y1; ++row) {
        const double yc = row + 0.5;
        uint64_t counters = kByteZero;
        for (int e = 0; e < n; ++e) {
            const glm::dvec2 a = v[e], b = v[e + 1 == n ? 0 : e + 1];
            const bool down = a.y < b.y;
            // The upper end's x by a mask, not a branch (the compiler made one of `down ? :`).
            const uint64_t pickA = uint64_t(0) - uint64_t(down);
            const uint64_t ax = std::bit_cast<uint64_t>(a.x), bx = std::bit_cast<uint64_t>(b.x);
            const double xTop = std::bit_cast<double>((ax & pickA) | (bx & ~pickA));
            const double xBottom = std::bit_cast<double>((bx & pickA) | (ax & ~pickA));
            const double yTop = std::min(a.y, b.y), yBottom = std::max(a.y, b.y);
            const bool active = (yTop <= yc) & (yc < yBottom);  // never a horizontal edge
            // An inactive edge's quotient may be inf or NaN: replaced before any rounding.
            const double x = active ? xTop + (yc - yTop) * (xBottom - xTop) / (yBottom - yTop) : 0.0;
            const int at = std::clamp(detail::firstCentreAtOrAfter(x, width) - column0, 0, 8);
            uint64_t step = at < 8 ? kByteOnes << (8 * (at & 7)) : 0;
            step = active ? step : 0;
            counters += down ? step : uint64_t(0) - step;
        }
        mask |= nonzeroBytes(counters ^ kByteZero) << (8 * (row & 7));
    }
    return (mask & ~word) != 0 && pyramid.coverTile(tx, ty, mask);
}

// Edge k of a polygon of n vertices runs from vertex from[n][k / 4][k % 4] to to[n][k / 4][k % 4]
// (k + 1, or 0 after the last); past the last edge both are vertex 0: a flat edge, which never
// counts. For the AVX2 path's registers of four edges, up to 8 edges.
struct EdgeEnds {
    uint8_t from[9][2][4], to[9][2][4];
    constexpr EdgeEnds() : from(), to() {
        for (int n = 1; n <= 8; ++n)
            for (int e = 0; e < 8; ++e) {
                from[n][e / 4][e % 4] = uint8_t(e < n ? e : 0);
                to[n][e / 4][e % 4] = uint8_t(e < n ? (e + 1 == n ? 0 : e + 1) : 0);
            }
    }
};
constexpr EdgeEnds kEdgeEnds{};

#if VDISO_HAS_AVX2_PATHS
// coverPolygonInTile with AVX2, four edges a register: per row, their four crossings made at
// once by the same operations in the same order (IEEE division; vroundpd's ceiling is exact),
// each edge's step to the tile's byte counters made by one variable shift (zero once the
// crossing lies right of the tile) and negated for an upward edge, and the four steps summed
// into the row's counters (64-bit sums of byte steps: the bytes never carry, as in the
// baseline's). Lanes past the last edge are flat and never count. Up to 8 edges.
VDISO_TARGET_AVX2 bool coverPolygonInTileAvx2(const glm::dvec2* v, int n, const PixelRect& rect, OcclusionPyramid& pyramid) {
    const int tx = rect.x0 >> 3, ty = rect.y0 >> 3;
    const uint64_t word = pyramid.tileWord(tx, ty);
    if (word == kFull) return false;
    const __m256d hi = _mm256_set1_pd(double(pyramid.width()) + 1.0);
    const __m256i tileColumn = _mm256_set1_epi64x(int64_t(tx) * 8), ones = _mm256_set1_epi64x(int64_t(kByteOnes));
    uint64_t counters[2] = {kByteZero, kByteZero};
    __m256d notFinite = _mm256_setzero_pd();  // x - x is not 0 for an infinity or a NaN
    for (int first = 0; first < n; first += 4) {
        // Built from scalars, not stored to an array and loaded: the wide load of four narrow
        // stores waits for them (it was a fifth of this function's time).
        const uint8_t* ia = kEdgeEnds.from[n][first >> 2];
        const uint8_t* ib = kEdgeEnds.to[n][first >> 2];
        const __m256d aX = _mm256_setr_pd(v[ia[0]].x, v[ia[1]].x, v[ia[2]].x, v[ia[3]].x);
        const __m256d aY = _mm256_setr_pd(v[ia[0]].y, v[ia[1]].y, v[ia[2]].y, v[ia[3]].y);
        const __m256d bX = _mm256_setr_pd(v[ib[0]].x, v[ib[1]].x, v[ib[2]].x, v[ib[3]].x);
        const __m256d bY = _mm256_setr_pd(v[ib[0]].y, v[ib[1]].y, v[ib[2]].y, v[ib[3]].y);
        notFinite = _mm256_or_pd(notFinite, _mm256_or_pd(_mm256_cmp_pd(_mm256_sub_pd(aX, aX), _mm256_setzero_pd(), _CMP_NEQ_UQ),
                                                         _mm256_cmp_pd(_mm256_sub_pd(aY, aY), _mm256_setzero_pd(), _CMP_NEQ_UQ)));
        const __m256d down = _mm256_cmp_pd(aY, bY, _CMP_LT_OQ);
        const __m256d xTop = _mm256_blendv_pd(bX, aX, down), xBottom = _mm256_blendv_pd(aX, bX, down);
        const __m256d yTop = _mm256_min_pd(aY, bY), yBottom = _mm256_max_pd(aY, bY);
        const __m256d dx = _mm256_sub_pd(xBottom, xTop), dy = _mm256_sub_pd(yBottom, yTop);
        const __m256i up = _mm256_castpd_si256(_mm256_cmp_pd(aY, bY, _CMP_NLT_UQ));  // all ones: negate
        for (int row = rect.y0; row <= rect.y1; ++row) {
            const __m256d yc = _mm256_set1_pd(row + 0.5);
            const __m256d active = _mm256_and_pd(_mm256_cmp_pd(yTop, yc, _CMP_LE_OQ), _mm256_cmp_pd(yc, yBottom, _CMP_LT_OQ));
            // An inactive edge's quotient may be inf or NaN: replaced before any rounding.
            const __m256d x = _mm256_and_pd(_mm256_add_pd(xTop, _mm256_div_pd(_mm256_mul_pd(_mm256_sub_pd(yc, yTop), dx), dy)), active);
            __m256i at = _mm256_sub_epi64(_mm256_cvtepi32_epi64(firstCentresAtOrAfter(x, hi)), tileColumn);
            at = _mm256_and_si256(at, _mm256_cmpgt_epi64(at, _mm256_setzero_si256()));  // at <= 0: every byte
            __m256i step = _mm256_and_si256(_mm256_sllv_epi64(ones, _mm256_slli_epi64(at, 3)), _mm256_castpd_si256(active));
            step = _mm256_sub_epi64(_mm256_xor_si256(step, up), up);
            const __m128i pair = _mm_add_epi64(_mm256_castsi256_si128(step), _mm256_extracti128_si256(step, 1));
            counters[row - rect.y0] += uint64_t(_mm_cvtsi128_si64(pair)) + uint64_t(_mm_extract_epi64(pair, 1));
        }
    }
    if (_mm256_movemask_pd(notFinite)) return false;  // as buildScanEdges: such a polygon covers nothing
    uint64_t mask = 0;
    for (int row = rect.y0; row <= rect.y1; ++row)
        mask |= nonzeroBytes(counters[row - rect.y0] ^ kByteZero) << (8 * (row & 7));
    return (mask & ~word) != 0 && pyramid.coverTile(tx, ty, mask);
}
#endif

}  // namespace

bool coverPolygonTiles(const glm::dvec2* v, int n, const PixelRect& rect, OcclusionPyramid& pyramid,
                       bool& newCentres, SimdLevel simd) {
    newCentres = false;
    if (n > kTileCoverageEdges) return false;
    if ((rect.x0 >> 3) == (rect.x1 >> 3) && (rect.y0 >> 3) == (rect.y1 >> 3) && rect.y1 - rect.y0 < 2) {
#if VDISO_HAS_AVX2_PATHS
        if (simd == SimdLevel::Avx2 && n <= 8) {
            newCentres = coverPolygonInTileAvx2(v, n, rect, pyramid);
            return true;
        }
#endif
        newCentres = coverPolygonInTile(v, n, rect, pyramid);
        return true;
    }
    detail::ScanEdge edges[kTileCoverageEdges];
    double yMin, yMax;
    const int edgeCount = detail::buildScanEdges(v, size_t(n), edges, yMin, yMax);
    if (edgeCount < 2) return true;  // not finite, or flat: scanConvertPolygon covers nothing too
    TileRow t{edges, edgeCount, 0, 0, 0, rect.x0 >> 3, rect.x1 >> 3, pyramid.width()};
    for (t.ty = rect.y0 >> 3; t.ty <= rect.y1 >> 3; ++t.ty) {
        t.row0 = std::max(rect.y0, t.ty * 8);
        t.row1 = std::min(rect.y1, t.ty * 8 + 7);
#if VDISO_HAS_AVX2_PATHS
        if (simd == SimdLevel::Avx2) {
            if (!coverTileRowSpansAvx2(t, pyramid, newCentres)) newCentres |= coverTileRowAvx2(t, pyramid);
            continue;
        }
#endif
        newCentres |= coverTileRowBaseline(t, pyramid);
    }
    return true;
}

}  // namespace vdiso
