// One TIFF file (multi-page or a single slice's page) through openTiffVolume: directories,
// page checks, strips and tiles, every codec libtiff was built with.
#include "fuzz/fuzz_input.h"
#include "fuzz/read_volume.h"
#include "io/readers/tiff_reader.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    vdiso::fuzz::MemoryFile file(data, size);
    vdiso::fuzz::expectAnswer([&] { vdiso::fuzz::readAllSlices(*vdiso::openTiffVolume(file.path())); });
    return 0;
}
