// Driving a generator of core/synth/synth.h: slices [z0, z0 + count) filled row by row on all cores
// through TBB, each row made in float by the model and rounded into the sample type. A model
// has a Scratch (per task, made from the model) and fillRow(y, z, scratch, out). Internal to
// the generators (synth_*.cpp).
#pragma once

#include <algorithm>
#include <cstdint>
#include <limits>
#include <type_traits>
#include <vector>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "core/volume.h"

namespace vdiso::synth_detail {

// Rounds to the nearest representable value, saturating; truncation after shifting to a
// non-negative range is a round-half-up that vectorises.
template <class T>
void storeRow(const float* values, int n, T* out) {
    if constexpr (std::is_same_v<T, float>) {
        std::copy(values, values + n, out);
    } else {
        constexpr float lo = float(std::numeric_limits<T>::min());
        constexpr float hi = float(std::numeric_limits<T>::max());
        for (int x = 0; x < n; ++x)
            out[x] = T(int32_t(std::min(std::max(values[x], lo), hi) - lo + 0.5f) + int32_t(lo));
    }
}

template <class Model, class T>
void generate(const Model& model, const Dims3& dims, int64_t z0, int64_t count, T* dst) {
    const int nx = int(dims[0]);
    const int64_t ny = dims[1];
    tbb::parallel_for(tbb::blocked_range<int64_t>(0, count * ny), [&](const auto& rows) {
        typename Model::Scratch scratch(model);
        std::vector<float> values(static_cast<size_t>(nx));
        for (int64_t r = rows.begin(); r != rows.end(); ++r) {
            model.fillRow(r % ny, z0 + r / ny, scratch, values.data());
            storeRow(values.data(), nx, dst + r * nx);
        }
    });
}

}  // namespace vdiso::synth_detail
