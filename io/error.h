// The one exception type for everything that crosses the process boundary.
//
// Every message names the file and what is wrong with it ("head.nrrd: unknown type 'quad'");
// the CLI prints what() as it is and exits non-zero.
#pragma once

#include <array>
#include <cstdint>
#include <stdexcept>
#include <string>

namespace vdiso {

class IoError : public std::runtime_error {
public:
    using std::runtime_error::runtime_error;
};

// Builds "path: message" and throws it as an IoError.
[[noreturn]] void throwIoError(const std::string& path, const std::string& message);

// Same, appending ": " and strerror(errnoValue).
[[noreturn]] void throwSystemError(const std::string& path, const std::string& message,
                                   int errnoValue);

// Throws "path: <what is wrong>" unless `dims` is within core/volume.h's limits. Every reader
// calls it before deriving a size from the dimensions.
void requireVolumeDims(const std::string& path, const std::array<int64_t, 3>& dims);

}  // namespace vdiso
