#include "core/lod/downsample.h"

#include <algorithm>
#include <cmath>
#include <type_traits>
#include <vector>

namespace vdiso {

namespace {

template <class T>
T fromAverage(float v) {
    if constexpr (std::is_floating_point_v<T>) {
        return T(v);
    } else {
        return T(std::floor(v + 0.5f));
    }
}

}  // namespace

template <class T>
void downsampleRows(const T* below, const T* at, const T* above, const Dims3& fine, const Dims3& coarse,
                    int64_t y0, int64_t y1, T* out) {
    static constexpr float kTent[3] = {0.25f, 0.5f, 0.25f};
    const int64_t nx = fine[0], ny = fine[1];
    const T* slices[3] = {below, at, above};
    // One fine row, filtered across the 3 x 3 fine rows around it (z, then y, summed in that
    // order from 0), then along x. One loop over the nine rows, which vectorises.
    std::vector<float> columnStorage(size_t(nx), 0.0f);
    float* __restrict column = columnStorage.data();
    for (int64_t y = y0; y < y1; ++y) {
        const T* rows[9];
        float w[9];
        for (int dz = 0; dz < 3; ++dz)
            for (int dy = 0; dy < 3; ++dy) {
                rows[dz * 3 + dy] = slices[dz] + std::clamp<int64_t>(2 * y + dy - 1, 0, ny - 1) * nx;
                w[dz * 3 + dy] = kTent[dz] * kTent[dy];
            }
        const T *__restrict r0 = rows[0], *__restrict r1 = rows[1], *__restrict r2 = rows[2], *__restrict r3 = rows[3],
                           *__restrict r4 = rows[4], *__restrict r5 = rows[5], *__restrict r6 = rows[6],
                           *__restrict r7 = rows[7], *__restrict r8 = rows[8];
        for (int64_t x = 0; x < nx; ++x) {
            float c = 0.0f;
            c += w[0] * float(r0[x]);
            c += w[1] * float(r1[x]);
            c += w[2] * float(r2[x]);
            c += w[3] * float(r3[x]);
            c += w[4] * float(r4[x]);
            c += w[5] * float(r5[x]);
            c += w[6] * float(r6[x]);
            c += w[7] * float(r7[x]);
            c += w[8] * float(r8[x]);
            column[x] = c;
        }
        T* o = out + y * coarse[0];
        for (int64_t x = 0; x < coarse[0]; ++x) {
            const int64_t l = std::clamp<int64_t>(2 * x - 1, 0, nx - 1), c = std::min(2 * x, nx - 1),
                          r = std::min(2 * x + 1, nx - 1);
            o[x] = fromAverage<T>(0.25f * column[l] + 0.5f * column[c] + 0.25f * column[r]);
        }
    }
}

template void downsampleRows<uint8_t>(const uint8_t*, const uint8_t*, const uint8_t*, const Dims3&, const Dims3&,
                                      int64_t, int64_t, uint8_t*);
template void downsampleRows<int16_t>(const int16_t*, const int16_t*, const int16_t*, const Dims3&, const Dims3&,
                                      int64_t, int64_t, int16_t*);
template void downsampleRows<uint16_t>(const uint16_t*, const uint16_t*, const uint16_t*, const Dims3&,
                                       const Dims3&, int64_t, int64_t, uint16_t*);
template void downsampleRows<float>(const float*, const float*, const float*, const Dims3&, const Dims3&, int64_t,
                                    int64_t, float*);

}  // namespace vdiso
