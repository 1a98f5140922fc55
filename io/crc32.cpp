#include "io/crc32.h"

#include <algorithm>

#include <zlib.h>

namespace vdiso {

uint32_t crc32Of(const void* data, size_t n) {
    uLong crc = crc32(0L, Z_NULL, 0);
    const auto* p = static_cast<const Bytef*>(data);
    while (n > 0) {  // zlib takes at most 4 GB a call
        const uInt chunk = uInt(std::min<size_t>(n, size_t(1) << 30));
        crc = crc32(crc, p, chunk);
        p += chunk;
        n -= chunk;
    }
    return uint32_t(crc);
}

}  // namespace vdiso
