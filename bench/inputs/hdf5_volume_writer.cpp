// An HDF5 volume written with libhdf5, a layer of chunks (a hyperslab of whole chunks) at a time,
// as tests/test_hdf5.cpp writes its small ones.
#include <hdf5.h>

#include <algorithm>
#include <stdexcept>
#include <vector>

#include "bench/inputs/writers.h"

namespace vdiso::bench {
namespace {

// Closes an HDF5 identifier when it goes out of scope.
struct Id {
    hid_t id;
    herr_t (*close)(hid_t);
    ~Id() {
        if (id >= 0) close(id);
    }
};

}  // namespace

void writeHdf5Volume(const HeadSlices& head, const std::string& path, int64_t chunk) {
    const int64_t n = head.size();
    auto fail = [&](const std::string& what) { throw std::runtime_error(path + ": " + what); };
    const Id file{H5Fcreate(path.c_str(), H5F_ACC_EXCL, H5P_DEFAULT, H5P_DEFAULT), H5Fclose};
    if (file.id < 0) fail("libhdf5 cannot create it");
    const hsize_t dims[3] = {hsize_t(n), hsize_t(n), hsize_t(n)};
    const Id space{H5Screate_simple(3, dims, nullptr), H5Sclose};
    const Id dcpl{H5Pcreate(H5P_DATASET_CREATE), H5Pclose};
    if (chunk > 0) {
        const hsize_t chunks[3] = {hsize_t(chunk), hsize_t(chunk), hsize_t(chunk)};
        H5Pset_chunk(dcpl.id, 3, chunks);
        H5Pset_shuffle(dcpl.id);  // before deflate: filters run in the order they are set
        H5Pset_deflate(dcpl.id, 1);
    }
    const Id dataset{H5Dcreate2(file.id, "/volume", H5T_STD_U16LE, space.id, H5P_DEFAULT, dcpl.id,
                                H5P_DEFAULT),
                     H5Dclose};
    if (dataset.id < 0) fail("libhdf5 cannot create /volume");
    // Layers of whole chunks: each chunk is compressed and written once, never read back.
    const int64_t layer = chunk > 0 ? chunk : 64;
    std::vector<uint16_t> slab(size_t(layer * n * n));
    for (int64_t z0 = 0; z0 < n; z0 += layer) {
        const int64_t depth = std::min(layer, n - z0);
        head.read(z0, depth, slab.data());
        const hsize_t start[3] = {hsize_t(z0), 0, 0}, size[3] = {hsize_t(depth), dims[1], dims[2]};
        const Id memory{H5Screate_simple(3, size, nullptr), H5Sclose};
        if (H5Sselect_hyperslab(space.id, H5S_SELECT_SET, start, nullptr, size, nullptr) < 0 ||
            H5Dwrite(dataset.id, H5T_NATIVE_UINT16, memory.id, space.id, H5P_DEFAULT, slab.data()) < 0)
            fail("libhdf5 cannot write slices " + std::to_string(z0) + " to " +
                 std::to_string(z0 + depth - 1));
    }
    if (H5Fflush(file.id, H5F_SCOPE_GLOBAL) < 0) fail("libhdf5 cannot flush it");
}

}  // namespace vdiso::bench
