// Run-time modules: libraries vdiso loads with dlopen on first use instead of linking them,
// because a linked library costs every command its loading (io/readers/vdb_module/vdb_module.h: OpenVDB
// took 35 ms; GDCM and HDF5 with what they pull in, 30 ms) though only one input format uses it.
//
// A module is looked for in VDISO_MODULE_DIR when that is set; otherwise beside the running
// executable (where the build puts it, next to vdiso), else in the build tree's directory for
// it (so tests and fuzz targets elsewhere find theirs). It is loaded once per process and stays.
#pragma once

#include <string>

namespace vdiso {

// The address of `symbol` in module `fileName` ("libvdiso_vdb.so"), loading the module if it is
// not yet. Throws IoError naming `path` (the file being read), `purpose` ("reading DICOM files")
// and the module when it cannot be found, does not load, or lacks the symbol.
void* runTimeModuleSymbol(const char* fileName, const char* symbol, const std::string& path,
                          const std::string& purpose);

}  // namespace vdiso
