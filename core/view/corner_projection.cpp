#include "core/view/corner_projection.h"

#include <algorithm>
#include <limits>

#if VDISO_HAS_AVX2_PATHS
#include <immintrin.h>
#endif

namespace vdiso {

CornerProjection::CornerProjection(const glm::dmat4& gridToClip, int width, int height, int metaCellSize,
                                   SimdLevel simd)
    : mSimd(simdLevelRuns(simd) ? simd : SimdLevel::Baseline), mWidth(width), mHeight(height), mImage(width, height),
      mSide(metaCellSize + 1) {
    for (int r = 0; r < 4; ++r) mRow[r] = {gridToClip[0][r], gridToClip[1][r], gridToClip[2][r], gridToClip[3][r]};
    const size_t corners = size_t(mSide) * size_t(mSide) * size_t(mSide);
    mClip.resize(corners);
    mPixel.resize(corners);
    mFront.assign(size_t(mSide) * size_t(mSide), 0);
    mBehind.assign(size_t(mSide) * size_t(mSide), 0);
    mEdgePixel.resize(3 * corners);
    mEdgeStamp.assign(3 * corners, 0);
}

void CornerProjection::project(const int64_t first[3], const uint64_t* rows) {
    if (++mStamp == 0) {  // wrapped: no stamp may match an old one
        std::fill(mEdgeStamp.begin(), mEdgeStamp.end(), 0u);
        mStamp = 1;
    }
#if VDISO_HAS_AVX2_PATHS
    if (mSimd == SimdLevel::Avx2) return projectAvx2(first, rows);
#endif
    const __m128d stepXY = _mm_set_pd(mRow[1].x, mRow[0].x), stepZW = _mm_set_pd(mRow[3].x, mRow[2].x);
    const __m128d half = _mm_set_pd(-0.5, 0.5), size = _mm_set_pd(mHeight, mWidth);
    for (int z = 0; z < mSide; ++z)
        for (int y = 0; y < mSide; ++y) {
            uint64_t bits = rows[z * mSide + y];
            if (bits == 0) continue;
            // One formula for every corner: ((w + z gz) + y gy) + x gx per row of the matrix.
            const double gy = double(first[1] + y), gz = double(first[2] + z);
            double base[4];
            for (int r = 0; r < 4; ++r) base[r] = (mRow[r].w + mRow[r].z * gz) + mRow[r].y * gy;
            const __m128d baseXY = _mm_loadu_pd(base), baseZW = _mm_loadu_pd(base + 2);
            uint64_t inFront = 0, behind = 0;  // of the row's corners projected now (the others keep their bits)
            const uint64_t projected = bits;
            double* clip = &mClip[size_t(cornerIndex(0, y, z))].x;
            double* pixel = &mPixel[size_t(cornerIndex(0, y, z))].x;
            for (; bits; bits &= bits - 1) {
                const int x = __builtin_ctzll(bits);
                const __m128d gx = _mm_set1_pd(double(first[0] + x));
                const __m128d xy = _mm_add_pd(baseXY, _mm_mul_pd(stepXY, gx));
                const __m128d zw = _mm_add_pd(baseZW, _mm_mul_pd(stepZW, gx));
                _mm_storeu_pd(clip + 4 * x, xy);
                _mm_storeu_pd(clip + 4 * x + 2, zw);
                // In front: w > 0 and z + w > 0 (lanes: z + w, w).
                const __m128d w = _mm_unpackhi_pd(zw, zw);
                const __m128d nearW = _mm_add_pd(zw, _mm_unpackhi_pd(zw, _mm_setzero_pd()));
                const int positive = _mm_movemask_pd(_mm_cmpgt_pd(nearW, _mm_setzero_pd()));
                inFront |= uint64_t(positive == 3) << x;
                behind |= uint64_t(_mm_movemask_pd(_mm_cmplt_pd(nearW, _mm_setzero_pd())) & 1) << x;
                // pixelOf: ((x, y) / w * (0.5, -0.5) + 0.5) * (width, height).
                const __m128d ndc = _mm_mul_pd(xy, _mm_div_pd(_mm_set1_pd(1.0), w));
                _mm_storeu_pd(pixel + 2 * x, _mm_mul_pd(_mm_add_pd(_mm_mul_pd(ndc, half), _mm_set1_pd(0.5)), size));
            }
            uint64_t& front = mFront[size_t(z * mSide + y)];
            front = (front & ~projected) | inFront;
            uint64_t& back = mBehind[size_t(z * mSide + y)];
            back = (back & ~projected) | behind;
        }
}

#if VDISO_HAS_AVX2_PATHS
// project() with AVX2: a corner's four clip coordinates in one register, each lane by the
// baseline's operations in its order (no fused multiply-add: the target is avx2 alone), and a
// row's base made for the four rows of the matrix at once the same way.
VDISO_TARGET_AVX2 void CornerProjection::projectAvx2(const int64_t first[3], const uint64_t* rows) {
    const __m256d rowW = _mm256_setr_pd(mRow[0].w, mRow[1].w, mRow[2].w, mRow[3].w);
    const __m256d rowZ = _mm256_setr_pd(mRow[0].z, mRow[1].z, mRow[2].z, mRow[3].z);
    const __m256d rowY = _mm256_setr_pd(mRow[0].y, mRow[1].y, mRow[2].y, mRow[3].y);
    const __m256d step = _mm256_setr_pd(mRow[0].x, mRow[1].x, mRow[2].x, mRow[3].x);
    const __m128d half = _mm_set_pd(-0.5, 0.5), size = _mm_set_pd(mHeight, mWidth), zero = _mm_setzero_pd();
    for (int z = 0; z < mSide; ++z) {
        const __m256d zTerm = _mm256_add_pd(rowW, _mm256_mul_pd(rowZ, _mm256_set1_pd(double(first[2] + z))));
        for (int y = 0; y < mSide; ++y) {
            uint64_t bits = rows[z * mSide + y];
            if (bits == 0) continue;
            const __m256d base = _mm256_add_pd(zTerm, _mm256_mul_pd(rowY, _mm256_set1_pd(double(first[1] + y))));
            uint64_t inFront = 0, behind = 0;
            const uint64_t projected = bits;
            double* clip = &mClip[size_t(cornerIndex(0, y, z))].x;
            double* pixel = &mPixel[size_t(cornerIndex(0, y, z))].x;
            for (; bits; bits &= bits - 1) {
                const int x = __builtin_ctzll(bits);
                const __m256d c = _mm256_add_pd(base, _mm256_mul_pd(step, _mm256_set1_pd(double(first[0] + x))));
                _mm256_storeu_pd(clip + 4 * x, c);
                const __m128d xy = _mm256_castpd256_pd128(c), zw = _mm256_extractf128_pd(c, 1);
                const __m128d w = _mm_unpackhi_pd(zw, zw);
                const __m128d nearW = _mm_add_pd(zw, _mm_unpackhi_pd(zw, zero));
                const int positive = _mm_movemask_pd(_mm_cmpgt_pd(nearW, zero));
                inFront |= uint64_t(positive == 3) << x;
                behind |= uint64_t(_mm_movemask_pd(_mm_cmplt_pd(nearW, zero)) & 1) << x;
                const __m128d ndc = _mm_mul_pd(xy, _mm_div_pd(_mm_set1_pd(1.0), w));
                _mm_storeu_pd(pixel + 2 * x, _mm_mul_pd(_mm_add_pd(_mm_mul_pd(ndc, half), _mm_set1_pd(0.5)), size));
            }
            uint64_t& front = mFront[size_t(z * mSide + y)];
            front = (front & ~projected) | inFront;
            uint64_t& back = mBehind[size_t(z * mSide + y)];
            back = (back & ~projected) | behind;
        }
    }
}
#endif

}  // namespace vdiso
