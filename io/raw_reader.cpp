#include "io/raw_reader.h"

#include "io/error.h"

namespace vdiso {

void StreamSliceDecoder::read(ByteStream& in, int64_t sliceSamples, int64_t count, void* dst) {
    const size_t inSize = fileScalarSize(mFileType);
    const size_t outSize = scalarSize(mStoreType);
    auto* out = static_cast<unsigned char*>(dst);
    // Samples already in the store's form go straight to dst: no scratch copy.
    if (!mSwap && !mScaled && mFileType == fileScalarOf(mStoreType)) {
        in.readExact(out, size_t(count) * size_t(sliceSamples) * outSize, "samples");
        return;
    }
    // A slice at a time bounds the scratch buffer by one slice, whatever the slab.
    mScratch.resize(size_t(sliceSamples) * inSize);
    for (int64_t s = 0; s < count; ++s) {
        in.readExact(mScratch.data(), mScratch.size(), "samples");
        decodeSamples(mScratch.data(), mFileType, mSwap, size_t(sliceSamples),
                      out + size_t(s) * size_t(sliceSamples) * outSize, mStoreType, mScaled,
                      mSlope, mIntercept);
    }
}

namespace {

class RawSliceReader final : public SliceReader {
public:
    RawSliceReader(const std::string& path, const RawOptions& o)
        : mPath(path),
          mDecoder(o.type, o.bigEndian != hostIsBigEndian(), storeTypeFor(o.type, false), false,
                   1.0, 0.0) {
        for (int a = 0; a < 3; ++a)
            if (o.dims[a] < 2)
                throwIoError(path, "dimension " + std::to_string(o.dims[a]) +
                                       " is too small: every axis needs at least 2 samples");
        mInfo.dims = o.dims;
        mInfo.type = storeTypeFor(o.type, false);
        mInfo.spacing = o.spacing;
        const uint64_t need = o.headerBytes + uint64_t(mInfo.sampleCount()) * fileScalarSize(o.type);
        const uint64_t have = fileSize(path);
        if (have != need) {
            const std::string dims = std::to_string(o.dims[0]) + "," + std::to_string(o.dims[1]) +
                                     "," + std::to_string(o.dims[2]);
            const std::string detail =
                " (dims " + dims + ", type " + fileScalarName(o.type) + ", header " +
                std::to_string(o.headerBytes) + " bytes need " + std::to_string(need) + ")";
            if (have < need)
                throwIoError(path, "file is " + std::to_string(need - have) +
                                       " bytes shorter than its dimensions" + detail);
            throwIoError(path, "file is " + std::to_string(have - need) +
                                   " bytes longer than its dimensions" + detail);
        }
        mIn = openFileStream(path, o.headerBytes);
    }
    const VolumeInfo& info() const override { return mInfo; }
    void read(void* dst, int64_t count) override {
        mDecoder.read(*mIn, mInfo.sliceSamples(), count, dst);
    }
    std::string name() const override { return mPath; }

private:
    std::string mPath;
    VolumeInfo mInfo;
    StreamSliceDecoder mDecoder;
    std::unique_ptr<ByteStream> mIn;
};

}  // namespace

std::unique_ptr<SliceReader> openRawVolume(const std::string& path, const RawOptions& options) {
    return std::make_unique<RawSliceReader>(path, options);
}

}  // namespace vdiso
