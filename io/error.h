// The one exception type for everything that crosses the process boundary.
//
// Every message names the file and what is wrong with it ("head.nrrd: unknown type 'quad'");
// the CLI prints what() as it is and exits non-zero.
#pragma once

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

}  // namespace vdiso
