// One HDF5 file through openHdf5Dataset with no dataset named: libhdf5's parsing of the
// superblock, object headers and B-trees as vdiso drives it, the search for the one 3-D
// dataset, filters, hyperslab reads of every slice.
#include "fuzz/fuzz_input.h"
#include "fuzz/read_volume.h"
#include "io/readers/hdf5_reader.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    vdiso::fuzz::MemoryFile file(data, size);
    vdiso::fuzz::expectAnswer([&] { vdiso::fuzz::readAllSlices(*vdiso::openHdf5Dataset(file.path(), "")); });
    return 0;
}
