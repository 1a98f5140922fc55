// Opening any supported input as a SliceReader: the one place that knows every format.
#pragma once

#include <memory>
#include <optional>
#include <string>

#include "core/synth.h"
#include "io/raw_reader.h"
#include "io/slice_reader.h"

namespace vdiso {

enum class InputFormat { Raw, Nrrd, Nifti, Vdb };

struct InputOptions {
    std::optional<RawOptions> raw;  // given: read `path` as raw with these options
    std::string grid;               // OpenVDB grid name (empty: the first float grid)
};

// Raw when options.raw is set; otherwise from the name: .nrrd/.nhdr, .nii/.nii.gz/.hdr, .vdb.
// Throws IoError for a name it does not recognise, saying how to read it as raw.
InputFormat detectInputFormat(const std::string& path, const InputOptions& options);

// Opens `path` in its format. Throws IoError naming the file on any problem.
std::unique_ptr<SliceReader> openVolume(const std::string& path, const InputOptions& options);

// The synthetic generators of core/synth.h as a source ("synth:head").
std::unique_ptr<SliceReader> openSynthVolume(const SynthParams& params);

}  // namespace vdiso
