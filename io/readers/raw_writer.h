// Writing a volume as a raw file (x fastest, native little-endian samples, no header),
// streaming slab by slab from any SliceReader; the file appears only when complete.
#pragma once

#include <cstdint>
#include <string>

#include "core/progress.h"
#include "io/readers/slice_reader.h"

namespace vdiso {

// Returns the bytes written. Throws IoError; on failure no output is left.
uint64_t writeRawVolume(SliceReader& source, const std::string& outPath, bool overwrite,
                        const ProgressFn& progress = {});

}  // namespace vdiso
