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
    // One fine row, filtered across the 3 x 3 fine rows around it (z, then y), then along x.
    std::vector<float> column(size_t(nx), 0.0f);
    for (int64_t y = y0; y < y1; ++y) {
        std::fill(column.begin(), column.end(), 0.0f);
        for (int dz = 0; dz < 3; ++dz)
            for (int dy = 0; dy < 3; ++dy) {
                const int64_t row = std::clamp<int64_t>(2 * y + dy - 1, 0, ny - 1);
                const T* in = slices[dz] + row * nx;
                const float w = kTent[dz] * kTent[dy];
                for (int64_t x = 0; x < nx; ++x) column[size_t(x)] += w * float(in[x]);
            }
        T* o = out + y * coarse[0];
        for (int64_t x = 0; x < coarse[0]; ++x) {
            const int64_t l = std::clamp<int64_t>(2 * x - 1, 0, nx - 1), c = std::min(2 * x, nx - 1),
                          r = std::min(2 * x + 1, nx - 1);
            o[x] = fromAverage<T>(0.25f * column[size_t(l)] + 0.5f * column[size_t(c)] + 0.25f * column[size_t(r)]);
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
