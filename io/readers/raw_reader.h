// Raw volumes: a header of headerBytes to skip, then dims[0]*dims[1]*dims[2] samples, x fastest.
#pragma once

#include <memory>
#include <string>

#include <vector>

#include "io/readers/byte_stream.h"
#include "io/readers/sample_decode.h"
#include "io/readers/slice_reader.h"

namespace vdiso {

struct RawOptions {
    Dims3 dims{0, 0, 0};
    FileScalar type = FileScalar::U8;
    glm::dvec3 spacing{1.0, 1.0, 1.0};
    bool bigEndian = false;
    uint64_t headerBytes = 0;
};

// Opens a raw file. The file's size must be exactly headerBytes plus the samples the
// dimensions call for: a shorter or longer file throws IoError saying by how many bytes.
std::unique_ptr<SliceReader> openRawVolume(const std::string& path, const RawOptions& options);

// Throws "<path>: file is N bytes shorter than <describedBy><detail>" (or "longer") for a file
// of `have` bytes that should hold `need` (have != need); shared by the raw, NRRD and NIfTI
// readers so their size errors read alike.
[[noreturn]] void throwFileSizeMismatch(const std::string& path, uint64_t have, uint64_t need,
                                        const std::string& describedBy, const std::string& detail);

// Reads `count` slices of `sliceSamples` samples from a byte stream and decodes them; shared by
// the raw, NRRD and NIfTI readers so the three convert samples one way.
class StreamSliceDecoder {
public:
    StreamSliceDecoder(FileScalar fileType, bool swapBytes, ScalarType storeType, bool scaled,
                       double slope, double intercept)
        : mFileType(fileType), mSwap(swapBytes), mStoreType(storeType), mScaled(scaled),
          mSlope(slope), mIntercept(intercept) {}
    void read(ByteStream& in, int64_t sliceSamples, int64_t count, void* dst);
    // Passes over `count` slices of `in` (ByteStream::skip: a seek, or decompression).
    void skip(ByteStream& in, int64_t sliceSamples, int64_t count) const;

private:
    FileScalar mFileType;
    bool mSwap;
    ScalarType mStoreType;
    bool mScaled;
    double mSlope, mIntercept;
    std::vector<unsigned char> mScratch;
};

// A SliceReader over `in`, decoding with `decoder`; `name` is what name() reports. With
// checkTrailingData, finish() throws if `in` holds more bytes: compressed input has no size to
// check up front, so only the last slice can tell it was longer than its header describes.
std::unique_ptr<SliceReader> openStreamSliceReader(std::string name, const VolumeInfo& info,
                                                   std::unique_ptr<ByteStream> in,
                                                   const StreamSliceDecoder& decoder,
                                                   bool checkTrailingData);

}  // namespace vdiso
