// The slices of an array-like (NumPy, Zarr, Dask, or anything with shape, dtype and slicing
// along axis 0), z = NumPy's axis 0, read in order as a SliceReader: what vdiso.convert and
// vdiso.marching_cubes read an array too large to load with. Each read takes the GIL, slices the
// object and checks what comes back before converting it to the store type.
#pragma once

#include <pybind11/pybind11.h>

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "io/readers/sample_decode.h"
#include "io/readers/slice_reader.h"

namespace vdiso::py {

class ArraySlices final : public SliceReader {
public:
    // `info`: the array's dimensions (x, y, z) in the store type that holds `type`, its spacing
    // and origin. `bounds`: where the source's chunks begin along axis 0, and its end (empty:
    // not chunked). Then whole chunks' slabs are read, so that a chunk is computed or decoded
    // once however the reads cut it, unless a chunk's slab would exceed kSlabBytes (then reads go
    // through as asked, bounded memory first).
    // Safe to make on a thread without the GIL (it takes it to hold `source`).
    ArraySlices(const pybind11::object& source, const VolumeInfo& info, FileScalar type, std::string name,
                std::vector<int64_t> bounds);
    static constexpr size_t kSlabBytes = size_t(512) << 20;
    ~ArraySlices() override;
    const VolumeInfo& info() const override { return mInfo; }
    std::string name() const override { return mName; }
    void read(void* dst, int64_t count) override;

private:
    void loadSlab(int64_t z);
    void readSource(void* dst, int64_t z, int64_t count);
    void checkShape(const pybind11::tuple& shape, int64_t count, const std::string& range) const;

    pybind11::object mSource;
    VolumeInfo mInfo;
    FileScalar mType;
    std::string mName;
    std::vector<int64_t> mBounds;
    std::vector<unsigned char> mSlab;  // slices [mSlabFirst, mSlabEnd): one chunk's
    int64_t mSlabFirst = 0, mSlabEnd = 0;
    int64_t mNext = 0;
};

// The VolumeInfo of an array of `shape` (z, y, x) and `type` (its store type), spacing (z, y, x)
// and origin (world x, y, z), checked: std::invalid_argument naming `name` or the setting.
VolumeInfo arrayVolumeInfo(const std::string& name, const std::vector<int64_t>& shape, FileScalar type,
                           std::array<double, 3> spacing, std::array<double, 3> origin);
// `bounds` (see ArraySlices) checked against `shape`: std::invalid_argument unless they start at
// 0, rise and end at the array's depth.
void checkChunkBounds(const std::string& name, const std::vector<int64_t>& shape, const std::vector<int64_t>& bounds);

}  // namespace vdiso::py
