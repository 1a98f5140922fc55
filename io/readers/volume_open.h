// Opening any supported input as a SliceReader: the one place that knows every format.
#pragma once

#include <memory>
#include <optional>
#include <string>

#include "core/synth/synth.h"
#include "io/readers/raw_reader.h"
#include "io/remote/remote_options.h"
#include "io/readers/slice_reader.h"

namespace vdiso {

enum class InputFormat { Raw, Nrrd, Nifti, Vdb, Tiff, Dicom, MetaImage, Hdf5, Zarr };

struct InputOptions {
    std::optional<RawOptions> raw;  // given: read `path` as raw with these options
    std::string grid;               // OpenVDB grid name (empty: the first float grid)
    // Replaces the spacing the input states (or lacks: TIFF has none); raw input takes its
    // spacing from `raw` instead.
    std::optional<glm::dvec3> spacing;
    std::string series;  // DICOM: the SeriesInstanceUID to read (empty: the only series)
    int scaleLevel = 0;  // OME-Zarr: the multiscales level to read (0: the finest)
    RemoteOptions remote;  // how a URL (Zarr, OME-Zarr) is reached
};

// Raw when options.raw is set; otherwise from the name: .nrrd/.nhdr, .nii/.nii.gz/.hdr, .vdb,
// .mha/.mhd, .h5/.hdf5 (FILE.h5:/dataset),
// .tif/.tiff, .dcm/.ima or DICOMDIR; a folder by what it holds (Zarr metadata: a Zarr array or
// OME-Zarr image; .tif/.tiff files: a TIFF stack; DICOM files, in it or its subfolders: a DICOM
// series); a glob pattern that
// names no file (quoted on the command line) is a stack of TIFF slices. A file with another
// name whose bytes start like a TIFF or a DICOM file is read as one. Throws IoError for an input it does not
// recognise, saying how to read it as raw.
// A URL (http://, https://, s3://) is Zarr or OME-Zarr, the formats read from the network.
InputFormat detectInputFormat(const std::string& path, const InputOptions& options);

// Opens `path` in its format. Throws IoError naming the file on any problem.
std::unique_ptr<SliceReader> openVolume(const std::string& path, const InputOptions& options);

// Opens one input (as openVolume) or a list of files that are each one slice or part of one:
// DICOM files of a series, or single-page TIFF slices (in the order given).
std::unique_ptr<SliceReader> openVolume(const std::vector<std::string>& paths,
                                        const InputOptions& options);

// The synthetic generators of core/synth/synth.h as a source ("synth:head").
std::unique_ptr<SliceReader> openSynthVolume(const SynthParams& params);

}  // namespace vdiso
