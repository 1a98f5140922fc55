// Raw volumes: a header of headerBytes to skip, then dims[0]*dims[1]*dims[2] samples, x fastest.
#pragma once

#include <memory>
#include <string>

#include <vector>

#include "io/byte_stream.h"
#include "io/sample_decode.h"
#include "io/slice_reader.h"

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

// Reads `count` slices of `sliceSamples` samples from a byte stream and decodes them; shared by
// the raw, NRRD and NIfTI readers so the three convert samples one way.
class StreamSliceDecoder {
public:
    StreamSliceDecoder(FileScalar fileType, bool swapBytes, ScalarType storeType, bool scaled,
                       double slope, double intercept)
        : mFileType(fileType), mSwap(swapBytes), mStoreType(storeType), mScaled(scaled),
          mSlope(slope), mIntercept(intercept) {}
    void read(ByteStream& in, int64_t sliceSamples, int64_t count, void* dst);

private:
    FileScalar mFileType;
    bool mSwap;
    ScalarType mStoreType;
    bool mScaled;
    double mSlope, mIntercept;
    std::vector<unsigned char> mScratch;
};

}  // namespace vdiso
