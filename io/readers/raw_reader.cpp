#include "io/readers/raw_reader.h"

#include <stdexcept>
#include <utility>

#include "core/checked_math.h"

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

void StreamSliceDecoder::skip(ByteStream& in, int64_t sliceSamples, int64_t count) const {
    if (count < 0) throw std::invalid_argument(in.path() + ": cannot skip a negative count of slices");
    in.skip(checkedMul(checkedMul(uint64_t(count), uint64_t(sliceSamples)), uint64_t(fileScalarSize(mFileType))));
}

void throwFileSizeMismatch(const std::string& path, uint64_t have, uint64_t need,
                           const std::string& describedBy, const std::string& detail) {
    if (have < need)
        throwIoError(path, "file is " + std::to_string(need - have) + " bytes shorter than " +
                               describedBy + detail);
    throwIoError(path, "file is " + std::to_string(have - need) + " bytes longer than " +
                           describedBy + detail);
}

namespace {

class StreamSliceReader final : public SliceReader {
public:
    StreamSliceReader(std::string name, const VolumeInfo& info, std::unique_ptr<ByteStream> in,
                      const StreamSliceDecoder& decoder, bool checkTrailingData)
        : mName(std::move(name)),
          mInfo(info),
          mIn(std::move(in)),
          mDecoder(decoder),
          mCheckTrailingData(checkTrailingData) {}

    const VolumeInfo& info() const override { return mInfo; }
    void read(void* dst, int64_t count) override {
        mDecoder.read(*mIn, mInfo.sliceSamples(), count, dst);
    }
    void skip(int64_t count) override { mDecoder.skip(*mIn, mInfo.sliceSamples(), count); }
    void finish() override {
        if (mCheckTrailingData && !mIn->atEnd())
            throwIoError(mIn->path(), "holds more data than its header describes");
    }
    std::string name() const override { return mName; }
    std::vector<std::string> files() const override { return {mName, mIn->path()}; }

private:
    std::string mName;
    VolumeInfo mInfo;
    std::unique_ptr<ByteStream> mIn;
    StreamSliceDecoder mDecoder;
    bool mCheckTrailingData;
};

VolumeInfo rawVolumeInfo(const std::string& path, const RawOptions& o) {
    for (int a = 0; a < 3; ++a)
        if (o.dims[a] < 2)
            throwIoError(path, "dimension " + std::to_string(o.dims[a]) +
                                   " is too small: every axis needs at least 2 samples");
    requireVolumeDims(path, o.dims);
    VolumeInfo info;
    info.dims = o.dims;
    info.type = storeTypeFor(o.type, false);
    info.spacing = o.spacing;
    return info;
}

// The file size is known up front, so a mismatch is reported before reading.
void checkRawFileSize(const std::string& path, const RawOptions& o, const VolumeInfo& info) {
    const uint64_t need = o.headerBytes + uint64_t(info.sampleCount()) * fileScalarSize(o.type);
    const uint64_t have = fileSize(path);
    if (have == need) return;
    const std::string dims = std::to_string(o.dims[0]) + "," + std::to_string(o.dims[1]) + "," +
                             std::to_string(o.dims[2]);
    const std::string detail = " (dims " + dims + ", type " + fileScalarName(o.type) + ", header " +
                               std::to_string(o.headerBytes) + " bytes need " +
                               std::to_string(need) + ")";
    throwFileSizeMismatch(path, have, need, "its dimensions", detail);
}

}  // namespace

std::unique_ptr<SliceReader> openStreamSliceReader(std::string name, const VolumeInfo& info,
                                                   std::unique_ptr<ByteStream> in,
                                                   const StreamSliceDecoder& decoder,
                                                   bool checkTrailingData) {
    return std::make_unique<StreamSliceReader>(std::move(name), info, std::move(in), decoder,
                                               checkTrailingData);
}

std::unique_ptr<SliceReader> openRawVolume(const std::string& path, const RawOptions& options) {
    const VolumeInfo info = rawVolumeInfo(path, options);
    checkRawFileSize(path, options, info);
    const StreamSliceDecoder decoder(options.type, options.bigEndian != hostIsBigEndian(),
                                     info.type, false, 1.0, 0.0);
    // The size was checked above, so there is no trailing data to look for.
    return openStreamSliceReader(path, info, openFileStream(path, options.headerBytes), decoder,
                                 false);
}

}  // namespace vdiso
