// NRRD headers and their data (attached, raw or gzip) through openNrrdVolume.
#include "fuzz/fuzz_input.h"
#include "fuzz/read_volume.h"
#include "io/readers/nrrd_reader.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    vdiso::fuzz::MemoryFile file(data, size);
    vdiso::fuzz::expectAnswer([&] { vdiso::fuzz::readAllSlices(*vdiso::openNrrdVolume(file.path())); });
    return 0;
}
