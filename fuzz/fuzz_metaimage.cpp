// One MetaImage file (.mha, LOCAL data raw or zlib) through openMetaImageVolume: header fields,
// sizes, HeaderSize, decompression, every slice.
#include "fuzz/fuzz_input.h"
#include "fuzz/read_volume.h"
#include "io/readers/metaimage_reader.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    vdiso::fuzz::MemoryFile file(data, size);
    vdiso::fuzz::expectAnswer([&] { vdiso::fuzz::readAllSlices(*vdiso::openMetaImageVolume(file.path())); });
    return 0;
}
