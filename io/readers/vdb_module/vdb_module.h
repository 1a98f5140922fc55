// The boundary between vdiso and its OpenVDB reader module (libvdiso_vdb.so).
//
// OpenVDB is a large C++ library: linked into the binary, resolving its symbols cost every
// command 35 ms at startup and 30 MB of memory, though only `vdiso convert` of a .vdb file
// uses it. So the reader lives in a module that io/readers/vdb_reader.cpp loads on first use, and the
// two meet at these C functions only: no C++ type, exception or allocation crosses.
#pragma once

#include <cstddef>
#include <cstdint>

extern "C" {

struct VdisoVdbVolume {
    int64_t dims[3];
    double spacing[3];
    double origin[3];
};

// Opens `path` and loads grid `grid` ("" for the first float or double grid); on success
// fills `volume` and returns a handle, else returns null with the reason (without the path)
// in err[0..errBytes).
void* vdiso_vdb_open(const char* path, const char* grid, VdisoVdbVolume* volume, char* err,
                     size_t errBytes);

// Writes z-slices [firstSlice, firstSlice + count) as floats, x fastest; returns 0, or -1 with
// the reason in err.
int vdiso_vdb_read(void* handle, int64_t firstSlice, int64_t count, float* dst, char* err,
                   size_t errBytes);

void vdiso_vdb_close(void* handle);

}  // extern "C"
