// NIfTI-1 files (plain or gzip) through openNiftiVolume.
#include "fuzz/fuzz_input.h"
#include "fuzz/read_volume.h"
#include "io/readers/nifti_reader.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    vdiso::fuzz::MemoryFile file(data, size);
    vdiso::fuzz::expectAnswer([&] { vdiso::fuzz::readAllSlices(*vdiso::openNiftiVolume(file.path())); });
    return 0;
}
