// Rectangles of pixel centres, and the roundings that make them from screen boxes two
// coordinates at a time (SSE2, the x86-64 baseline): a tree node's or meta-cell's box
// (boxCentres, ViewCuller's test), a cell's from its projected corners, a polygon's slack and
// centre rectangles from its vertices. The integers are those of the scalar roundings written
// one coordinate at a time (scan_convert.h's firstCentreAtOrAfter, pixel_round.h's ceil and
// floor by truncation), to the bit: the same operations in the same order on each coordinate
// (tests/test_pixel_rect.cpp). Every crossed cell and polygon of a visible meta-cell asks for
// these; rounded one coordinate at a time they were about a fifth of the visibility work's
// instructions.
#pragma once

#include <algorithm>

#include <emmintrin.h>

#include <glm/vec2.hpp>

namespace vdiso {

// Pixel centres [x0, x1] x [y0, y1] (inclusive; possibly empty, possibly off the image).
struct PixelRect {
    int x0, y0, x1, y1;
    bool empty() const { return x0 > x1 || y0 > y1; }
    bool overlaps(const PixelRect& o) const { return x0 <= o.x1 && o.x0 <= x1 && y0 <= o.y1 && o.y0 <= y1; }
    PixelRect intersection(const PixelRect& o) const {
        return {std::max(x0, o.x0), std::max(y0, o.y0), std::min(x1, o.x1), std::min(y1, o.y1)};
    }
};

// GL's sub-pixel snapping is 1/256 or finer: a polygon's rasterizer-rounding check
// (core/view/polygon_coverage.h) looks this far beyond its box.
constexpr double kRasterSlack = 1.0 / 64;

namespace detail {

// ceil and floor of two doubles of magnitude below 2^31, as int32 lanes 0 and 1 (pixel_round.h's
// ceilToInt and floorToInt: truncation, then one step where it went the wrong way).
inline __m128i ceilLanes(__m128d x) {
    const __m128i i = _mm_cvttpd_epi32(x);
    const __m128d below = _mm_cmplt_pd(_mm_cvtepi32_pd(i), x);  // all ones: add 1
    return _mm_sub_epi32(i, _mm_shuffle_epi32(_mm_castpd_si128(below), _MM_SHUFFLE(3, 3, 2, 0)));
}
inline __m128i floorLanes(__m128d x) {
    const __m128i i = _mm_cvttpd_epi32(x);
    const __m128d above = _mm_cmpgt_pd(_mm_cvtepi32_pd(i), x);
    return _mm_add_epi32(i, _mm_shuffle_epi32(_mm_castpd_si128(above), _MM_SHUFFLE(3, 3, 2, 0)));
}
// std::clamp(v, lo, hi) for lanes that are not NaN.
inline __m128d clampLanes(__m128d v, __m128d lo, __m128d hi) { return _mm_min_pd(_mm_max_pd(v, lo), hi); }

inline PixelRect rectOf(__m128i lo, __m128i hi) {
    return {_mm_cvtsi128_si32(lo), _mm_cvtsi128_si32(_mm_shuffle_epi32(lo, 1)), _mm_cvtsi128_si32(hi),
            _mm_cvtsi128_si32(_mm_shuffle_epi32(hi, 1))};
}
inline __m128i maxLanes(__m128i a, __m128i b) {  // SSE2 has no pmaxsd
    const __m128i aGreater = _mm_cmpgt_epi32(a, b);
    return _mm_or_si128(_mm_and_si128(aGreater, a), _mm_andnot_si128(aGreater, b));
}
inline __m128i minLanes(__m128i a, __m128i b) {
    const __m128i aGreater = _mm_cmpgt_epi32(a, b);
    return _mm_or_si128(_mm_and_si128(aGreater, b), _mm_andnot_si128(aGreater, a));
}

}  // namespace detail

// Lanes (x, y) of the image's size, as doubles and as int32 lanes less one.
struct ImageLanes {
    __m128d size;
    __m128i last;
    ImageLanes(int width, int height)
        : size(_mm_setr_pd(width, height)), last(_mm_setr_epi32(width - 1, height - 1, 0, 0)) {}
};

namespace detail {
// The first centre at or after each lane of lo and the last at or before each lane of hi, each
// end clamped to [-1, size] first (a box far off the image holds no int).
inline void centreLanes(__m128d lo, __m128d hi, const ImageLanes& image, __m128i& first, __m128i& last) {
    const __m128d half = _mm_set1_pd(0.5), minusOne = _mm_set1_pd(-1.0);
    first = ceilLanes(clampLanes(_mm_sub_pd(lo, half), minusOne, image.size));
    last = floorLanes(clampLanes(_mm_sub_pd(hi, half), minusOne, image.size));
}
}  // namespace detail

// The pixel centres of the box [lo, hi] (lanes x, y; not NaN): columns from the first centre at
// or after lo.x to the last at or before hi.x, rows likewise (each within a pixel of the image).
inline PixelRect boxCentres(__m128d lo, __m128d hi, const ImageLanes& image) {
    __m128i first, last;
    detail::centreLanes(lo, hi, image, first, last);
    return detail::rectOf(first, last);
}
// boxCentres clamped to the image (as OcclusionPyramid::isOccluded clamps): empty when none of
// them lies on it.
inline PixelRect boxCentresOnImage(__m128d lo, __m128d hi, const ImageLanes& image) {
    __m128i first, last;
    detail::centreLanes(lo, hi, image, first, last);
    return detail::rectOf(detail::maxLanes(first, _mm_setzero_si128()), detail::minLanes(last, image.last));
}

// A polygon's slack rectangle (the centres within kRasterSlack of its box, where
// PolygonCoverage looks first) and centre rectangle (the centres it can cover: centresOfBox),
// both clamped to the image, from its n >= 1 vertices (finite, pixel coordinates).
[[gnu::always_inline]] inline void polygonRects(const glm::dvec2* v, int n, const ImageLanes& image, PixelRect& slack, PixelRect& centres) {
    __m128d lo = _mm_loadu_pd(&v[0].x), hi = lo;
    for (int k = 1; k < n; ++k) {
        const __m128d p = _mm_loadu_pd(&v[k].x);
        lo = _mm_min_pd(lo, p);
        hi = _mm_max_pd(hi, p);
    }
    const __m128d half = _mm_set1_pd(0.5), zero = _mm_setzero_pd(), minusOne = _mm_set1_pd(-1.0);
    const __m128d s = _mm_set1_pd(kRasterSlack), one = _mm_set1_pd(1.0);
    const __m128d sizeLess1 = _mm_sub_pd(image.size, one), sizeMore1 = _mm_add_pd(image.size, one);
    slack = detail::rectOf(detail::ceilLanes(detail::clampLanes(_mm_sub_pd(_mm_sub_pd(lo, s), half), zero, image.size)),
                           detail::floorLanes(detail::clampLanes(_mm_sub_pd(_mm_add_pd(hi, s), half), minusOne, sizeLess1)));
    // scan_convert.h's firstCentreAtOrAfter at each end; the upper one's centre is the last before.
    const __m128i first = detail::ceilLanes(_mm_sub_pd(detail::clampLanes(lo, minusOne, sizeMore1), half));
    const __m128i after = detail::ceilLanes(_mm_sub_pd(detail::clampLanes(hi, minusOne, sizeMore1), half));
    centres = detail::rectOf(detail::maxLanes(first, _mm_setzero_si128()),
                             detail::minLanes(_mm_sub_epi32(after, _mm_set1_epi32(1)), image.last));
}

}  // namespace vdiso
