// A SliceReader that runs in a helper process (io/readers/helper_process.h): for readers built on a
// library that cannot be trusted with damaged files (libhdf5).
//
// `open` runs in the child, with the child's data memory bounded; once it has returned, the
// bound is lifted and the child serves reads, sending each slice's samples back through the
// socket (one copy per slice). An IoError raised in the child arrives with its message as it
// was; the child dying (a crash, an abort, memory it could not get) is an IoError naming `name`,
// `library` and how the child ended. Not thread-safe: one reader, one process.
#pragma once

#include <functional>
#include <memory>
#include <string>

#include "io/readers/slice_reader.h"

namespace vdiso {

std::unique_ptr<SliceReader> openIsolatedReader(
    const std::string& name, const std::string& library,
    const std::function<std::unique_ptr<SliceReader>()>& open);

}  // namespace vdiso
