#include "io/readers/edge_padded_reader.h"

#include <algorithm>
#include <cstring>
#include <stdexcept>
#include <vector>

#include "io/error.h"

namespace vdiso {
namespace {

class EdgePaddedReader final : public SliceReader {
public:
    EdgePaddedReader(std::unique_ptr<SliceReader> source, const Dims3& dims)
        : mSource(std::move(source)), mInfo(mSource->info()) {
        mSourceDims = mInfo.dims;
        mInfo.dims = dims;
        mSampleBytes = scalarSize(mInfo.type);
        mSourceSlice.resize(size_t(mSourceDims[0] * mSourceDims[1]) * mSampleBytes);
        mLastSlice.resize(size_t(dims[0] * dims[1]) * mSampleBytes);
    }

    const VolumeInfo& info() const override { return mInfo; }
    std::string name() const override { return mSource->name(); }
    std::vector<std::string> files() const override { return mSource->files(); }
    void finish() override { mSource->finish(); }

    void read(void* dst, int64_t count) override {
        auto* out = static_cast<unsigned char*>(dst);
        const size_t sliceBytes = mLastSlice.size();
        for (int64_t s = 0; s < count; ++s, ++mNext) {
            if (mNext >= mInfo.dims[2]) throwIoError(name(), "has fewer slices than asked for");
            if (mNext < mSourceDims[2]) readSourceSlice();
            std::memcpy(out + size_t(s) * sliceBytes, mLastSlice.data(), sliceBytes);
        }
    }

    void skip(int64_t count) override {
        if (count < 0 || count > mInfo.dims[2] - mNext) throwIoError(name(), "has fewer slices than asked for");
        const int64_t fromSource = std::clamp<int64_t>(mSourceDims[2] - mNext, 0, count);
        // The source's last slice is read when the slices after it repeat it.
        if (fromSource > 0 && mNext + count > mSourceDims[2]) {
            mSource->skip(fromSource - 1);
            readSourceSlice();
        } else if (fromSource > 0) {
            mSource->skip(fromSource);
        }
        mNext += count;
    }

private:
    // The source's next slice, padded, into mLastSlice.
    void readSourceSlice() {
        mSource->read(mSourceSlice.data(), 1);
        const int64_t nx = mInfo.dims[0], ny = mInfo.dims[1], sx = mSourceDims[0], sy = mSourceDims[1];
        const size_t b = mSampleBytes;
        for (int64_t y = 0; y < ny; ++y) {
            unsigned char* row = mLastSlice.data() + size_t(y * nx) * b;
            if (y >= sy) {
                std::memcpy(row, row - size_t(nx) * b, size_t(nx) * b);
                continue;
            }
            std::memcpy(row, mSourceSlice.data() + size_t(y * sx) * b, size_t(sx) * b);
            for (int64_t x = sx; x < nx; ++x) std::memcpy(row + size_t(x) * b, row + size_t(sx - 1) * b, b);
        }
    }

    std::unique_ptr<SliceReader> mSource;
    VolumeInfo mInfo;
    Dims3 mSourceDims{};
    size_t mSampleBytes = 0;
    std::vector<unsigned char> mSourceSlice, mLastSlice;
    int64_t mNext = 0;
};

}  // namespace

std::unique_ptr<SliceReader> edgePaddedReader(std::unique_ptr<SliceReader> source, const Dims3& dims) {
    const Dims3 own = source->info().dims;
    for (int a = 0; a < 3; ++a)
        if (dims[a] < own[a] || own[a] < 1) throw std::logic_error("edgePaddedReader: a volume smaller than its source");
    if (dims == own) return source;
    return std::make_unique<EdgePaddedReader>(std::move(source), dims);
}

}  // namespace vdiso
