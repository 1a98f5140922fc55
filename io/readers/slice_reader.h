// The streaming input side of conversion: a volume delivered a few z-slices at a time.
//
// Every input format (raw, NRRD, NIfTI, OpenVDB, the synthetic generators) is opened as a
// SliceReader, so conversion never holds more than the slab it is working on. Samples arrive
// converted to info().type in native byte order. One virtual call per slab, not per sample.
//
// skip() passes over slices without delivering them, so that a rank of an MPI job converting
// its slab (mpi/convert_across_ranks.h) starts where its slab does. It is cheap where the
// format allows: a seek in raw, NRRD, NIfTI and MetaImage files stored uncompressed, a page
// or file count in TIFF stacks and DICOM series, a slice counter for Zarr chunks, HDF5
// hyperslabs, OpenVDB grids and the synthetic generators. A compressed stream (gzip: .nii.gz,
// NRRD and MetaImage with gzip encoding) has no index to seek by: skipping decompresses all it
// passes over, so every rank decompresses the input up to its slab.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "core/volume.h"

namespace vdiso {

class SliceReader {
public:
    virtual ~SliceReader() = default;

    // Dimensions, store type, spacing and origin; valid as soon as the reader is open.
    virtual const VolumeInfo& info() const = 0;

    // Reads the next `count` z-slices into dst (count * dims[0] * dims[1] samples of
    // info().type). Throws IoError naming the file if the input ends early or is corrupt.
    virtual void read(void* dst, int64_t count) = 0;

    // Passes over the next `count` z-slices (count >= 0) as read() would, without delivering
    // them; throws what read() would if the input ends early or is corrupt there (a compressed
    // stream is checked as it is decompressed; a seek only checks the file's size). The default
    // reads and discards them, 16 MiB or one slice at a time.
    virtual void skip(int64_t count);

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
