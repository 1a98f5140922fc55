// Reading a small text file (camera JSON, camera paths) whole, with a bound: a file larger than
// `maxBytes` (or an endless one such as /dev/zero) is refused after reading at most
// maxBytes + 1 bytes, never read into memory whole.
#pragma once

#include <cstddef>
#include <string>

namespace vdiso {

// The file's bytes. Throws IoError naming the file if it cannot be opened or read, or if it
// holds more than `maxBytes` bytes (`what` names the kind of file in that message).
std::string readBoundedText(const std::string& path, size_t maxBytes, const std::string& what);

}  // namespace vdiso
