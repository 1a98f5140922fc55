// The boundary between vdiso and its HDF5 module (libvdiso_hdf5_module.so).
//
// libhdf5 (Debian's pulls in libcurl, GnuTLS, Kerberos, LDAP...) linked into the binary made
// every command start in ~30 ms instead of ~3 ms with GDCM's share, though only HDF5 input
// uses it. So io/readers/hdf5_reader.cpp loads this module on first use and calls it in its helper
// process (io/readers/isolated_reader.h), and the two meet at these C functions only: no C++ type,
// exception or allocation crosses. Error messages come whole, naming the file (and dataset).
#pragma once

#include <cstddef>
#include <cstdint>

#define VDISO_HDF5_API __attribute__((visibility("default")))

extern "C" {

// Sample types, as io/readers/sample_decode.h's FileScalar numbers them.
enum { VDISO_HDF5_I8, VDISO_HDF5_U8, VDISO_HDF5_I16, VDISO_HDF5_U16, VDISO_HDF5_I32,
       VDISO_HDF5_U32, VDISO_HDF5_F32, VDISO_HDF5_F64 };

struct VdisoHdf5Dataset {
    int64_t dims[3];        // x, y, z (the dataset's last dimension is x)
    int sampleType;         // VDISO_HDF5_*
    int hasSpacing;         // element_size_um was there and valid
    double spacing[3];      // x, y, z, when hasSpacing
    char name[1024];        // the dataset's path in the file ("/volume"), chosen when not given
};

// Opens `dataset` of `file` ("" for the only 3-D numeric dataset); on success fills `out` and
// returns a handle, else returns null with the message ("FILE: ..." or "FILE:/dataset: ...")
// in err[0..errBytes).
VDISO_HDF5_API void* vdiso_hdf5_open(const char* file, const char* dataset, VdisoHdf5Dataset* out,
                                     char* err, size_t errBytes);

// Reads z-slices [firstSlice, firstSlice + count) into dst as the dataset's sample type in
// native byte order, x fastest; returns 0, or -1 with the message in err.
VDISO_HDF5_API int vdiso_hdf5_read(void* handle, int64_t firstSlice, int64_t count, void* dst,
                                   char* err, size_t errBytes);

VDISO_HDF5_API void vdiso_hdf5_close(void* handle);

}  // extern "C"
