#include "io/error.h"

#include <cstring>

#include "core/volume.h"

namespace vdiso {

void throwIoError(const std::string& path, const std::string& message) {
    std::string text;
    text.reserve(path.size() + 2 + message.size());
    text.append(path).append(": ").append(message);
    throw IoError(text);
}

void throwSystemError(const std::string& path, const std::string& message, int errnoValue) {
    throwIoError(path, message + ": " + std::strerror(errnoValue));
}

void requireVolumeDims(const std::string& path, const std::array<int64_t, 3>& dims) {
    const std::string problem = volumeDimsProblem(dims);
    if (!problem.empty()) throwIoError(path, problem);
}

}  // namespace vdiso
