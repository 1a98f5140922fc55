// One DICOM file through the reader's file level (openDicomImage): the structure check that
// guards GDCM, the header fields, and the pixel data decoded by GDCM in its transfer syntax.
// Series assembly (order, gaps, type) is covered by tests on headers alone (test_dicom.cpp).
#include "fuzz/fuzz_input.h"
#include "fuzz/read_volume.h"
#include "io/readers/dicom_reader.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    vdiso::fuzz::MemoryFile file(data, size);
    vdiso::fuzz::expectAnswer([&] { vdiso::fuzz::readAllSlices(*vdiso::openDicomImage(file.path())); });
    return 0;
}
