// Reads what a fuzzed SliceReader delivers, slice by slice, within a fixed memory bound: the
// reader's own checks decide, not the harness's allocation.
#pragma once

#include <cstdint>
#include <vector>

#include "core/scalar_type.h"
#include "io/readers/slice_reader.h"

namespace vdiso::fuzz {

inline void readAllSlices(SliceReader& reader) {
    constexpr uint64_t kMaxSliceBytes = uint64_t(64) << 20;
    const VolumeInfo& info = reader.info();
    const uint64_t sliceBytes = uint64_t(info.dims[0]) * uint64_t(info.dims[1]) * scalarSize(info.type);
    if (sliceBytes == 0 || sliceBytes > kMaxSliceBytes) return;  // the reader accepted it: fine
    std::vector<unsigned char> slice(sliceBytes);
    for (int64_t z = 0; z < info.dims[2] && z < 4096; ++z) reader.read(slice.data(), 1);
    reader.finish();
}

}  // namespace vdiso::fuzz
