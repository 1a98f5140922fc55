#include "io/text_file.h"

#include <cerrno>
#include <cstdio>
#include <memory>

#include "io/error.h"

namespace vdiso {

std::string readBoundedText(const std::string& path, size_t maxBytes, const std::string& what) {
    std::unique_ptr<FILE, int (*)(FILE*)> f(std::fopen(path.c_str(), "rb"), &std::fclose);
    if (!f) throwSystemError(path, "cannot open", errno);
    std::string text;
    char buf[65536];
    for (;;) {
        const size_t n = std::fread(buf, 1, sizeof buf, f.get());
        text.append(buf, n);
        if (text.size() > maxBytes)
            throwIoError(path, "is larger than " + std::to_string(maxBytes) + " bytes, the most " +
                                   what + " may hold");
        if (n < sizeof buf) break;
    }
    if (std::ferror(f.get())) throwSystemError(path, "cannot read", errno);
    return text;
}

}  // namespace vdiso
