#include "io/crc32.h"

#include <algorithm>
#include <array>

#include <zlib.h>

namespace vdiso {

uint32_t crc32Of(const void* data, size_t n) { return crc32Update(uint32_t(crc32(0L, Z_NULL, 0)), data, n); }

uint32_t crc32Update(uint32_t start, const void* data, size_t n) {
    uLong crc = start;
    const auto* p = static_cast<const Bytef*>(data);
    while (n > 0) {  // zlib takes at most 4 GB a call
        const uInt chunk = uInt(std::min<size_t>(n, size_t(1) << 30));
        crc = crc32(crc, p, chunk);
        p += chunk;
        n -= chunk;
    }
    return uint32_t(crc);
}

uint32_t crc32cOf(const void* data, size_t n) {
    static const auto table = [] {
        std::array<uint32_t, 256> t{};
        for (uint32_t i = 0; i < 256; ++i) {
            uint32_t c = i;
            for (int k = 0; k < 8; ++k) c = c & 1 ? (c >> 1) ^ 0x82F63B78u : c >> 1;  // reflected 0x1EDC6F41
            t[i] = c;
        }
        return t;
    }();
    uint32_t crc = ~0u;
    const auto* p = static_cast<const unsigned char*>(data);
    for (size_t i = 0; i < n; ++i) crc = table[(crc ^ p[i]) & 0xffu] ^ (crc >> 8);
    return ~crc;
}

}  // namespace vdiso
