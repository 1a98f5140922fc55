// The streaming input side of conversion: a volume delivered a few z-slices at a time.
//
// Every input format (raw, NRRD, NIfTI, OpenVDB, the synthetic generators) is opened as a
// SliceReader, so conversion never holds more than the slab it is working on. Samples arrive
// converted to info().type in native byte order. One virtual call per slab, not per sample.
#pragma once

#include <cstdint>
#include <memory>
#include <string>

#include "core/volume.h"

#include <string>
#include <vector>

namespace vdiso {

class SliceReader {
public:
    virtual ~SliceReader() = default;

    // Dimensions, store type, spacing and origin; valid as soon as the reader is open.
    virtual const VolumeInfo& info() const = 0;

    // Reads the next `count` z-slices into dst (count * dims[0] * dims[1] samples of
    // info().type). Throws IoError naming the file if the input ends early or is corrupt.
    virtual void read(void* dst, int64_t count) = 0;

    // Called once after the last slice: throws IoError if the input holds more samples than its
    // dimensions say (a wrong --dims, a mismatched header).
    virtual void finish() {}

    // Where the samples come from, for messages ("head.nii.gz", "synth:head").
    virtual std::string name() const = 0;

    // The files the volume is read from (a header and its data file, when they differ); none
    // for generated or in-memory volumes. A writer refuses to replace any of them.
    virtual std::vector<std::string> files() const { return {}; }
};

}  // namespace vdiso
