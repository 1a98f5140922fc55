// Raw volumes: the header arguments (--dims, --type, --endian, --header-bytes) from the first
// 32 bytes of the input, the file from the rest.
#include <cstring>

#include "fuzz/fuzz_input.h"
#include "fuzz/read_volume.h"
#include "io/readers/raw_reader.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    constexpr size_t kArgs = 32;
    if (size < kArgs) return 0;
    vdiso::RawOptions o;
    for (int k = 0; k < 3; ++k) {
        int64_t d;
        std::memcpy(&d, data + 8 * k, 8);
        o.dims[size_t(k)] = d;
    }
    o.type = vdiso::FileScalar(data[24] % 8);
    o.bigEndian = data[25] & 1;
    uint32_t header;
    std::memcpy(&header, data + 28, 4);
    o.headerBytes = header;
    vdiso::fuzz::MemoryFile file(data + kArgs, size - kArgs);
    vdiso::fuzz::expectAnswer([&] { vdiso::fuzz::readAllSlices(*vdiso::openRawVolume(file.path(), o)); });
    return 0;
}
