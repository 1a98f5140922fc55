// The boundary between vdiso and its GDCM module (libvdiso_gdcm_module.so).
//
// GDCM and what it links (CharLS, OpenJPEG, its data dictionary's static initialisers), linked
// into the binary, made every command start in ~30 ms instead of ~3 ms with HDF5's share,
// though only DICOM input uses them, and only in the helper process io/readers/gdcm_process.h forks.
// So io/readers/gdcm_process.cpp loads this module on first use and its helper hands the module its
// socket: the module serves the requests until the socket closes. What crosses is a file
// descriptor and the bytes on it (the protocol in gdcm_module.cpp, encoded with
// io/readers/helper_wire.h and io/readers/dicom_wire.h): no C++ type, exception or allocation.
#pragma once

extern "C" {

// Serves header ('H'), DICOMDIR ('D') and pixel ('P') requests on `fd` until the peer closes
// it or a reply cannot be sent; returns 0 then. Never throws.
__attribute__((visibility("default"))) int vdiso_gdcm_serve(int fd);

}  // extern "C"
