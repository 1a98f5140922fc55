#include "io/readers/jpeg_frame_header.h"

namespace vdiso {

std::optional<JpegFrameHeader> readJpegFrameHeader(const unsigned char* b, size_t n) {
    if (n < 2 || b[0] != 0xff || b[1] != 0xd8) return std::nullopt;
    size_t at = 2;
    while (at + 4 <= n) {
        if (b[at] != 0xff) return std::nullopt;
        const unsigned marker = b[at + 1];
        if (marker == 0xff) {  // fill byte
            ++at;
            continue;
        }
        if (marker == 0x01 || (marker >= 0xd0 && marker <= 0xd7)) {  // no length
            at += 2;
            continue;
        }
        if (marker == 0xda || marker == 0xd9) return std::nullopt;  // a scan (or the end) first
        const size_t length = size_t(b[at + 2]) << 8 | b[at + 3];
        const bool frame = (marker >= 0xc0 && marker <= 0xcf && marker != 0xc4 && marker != 0xc8 &&
                            marker != 0xcc) ||
                           marker == 0xf7;
        if (frame) {
            if (length < 8 || at + 2 + length > n) return std::nullopt;
            const unsigned char* p = b + at + 4;
            JpegFrameHeader h;
            h.precision = p[0];
            h.lines = uint32_t(p[1]) << 8 | p[2];
            h.columns = uint32_t(p[3]) << 8 | p[4];
            h.components = p[5];
            return h;
        }
        if (length < 2) return std::nullopt;
        at += 2 + length;
    }
    return std::nullopt;
}

}  // namespace vdiso
