// A DicomHeader as it travels between io/readers/gdcm_process.cpp and the GDCM module that serves it
// (io/readers/gdcm_module/gdcm_module.h). Inline: the module builds it without linking vdiso_io.
#pragma once

#include <cstdint>
#include <string>

#include "io/readers/dicom_series.h"
#include "io/readers/helper_wire.h"

namespace vdiso {

inline void putDicomHeader(WireWriter& w, const DicomHeader& h) {
    w.put(h.seriesUid).put(h.seriesDescription).put(h.modality).put(h.transferSyntax);
    w.put(h.rows).put(h.columns).put(uint8_t(h.pixelType)).put(int32_t(h.bitsStored));
    w.put(h.position).put(h.orientation).put(h.pixelSpacing).put(h.sliceSpacing);
    w.put(h.instanceNumber).put(h.slope).put(h.intercept).put(h.problem);
}

// Throws std::runtime_error on a short message.
inline DicomHeader getDicomHeader(const std::string& bytes, const std::string& path) {
    WireReader r(bytes);
    DicomHeader h;
    h.path = path;
    uint8_t type = 0;
    int32_t bitsStored = 0;
    r.get(h.seriesUid);
    r.get(h.seriesDescription);
    r.get(h.modality);
    r.get(h.transferSyntax);
    r.get(h.rows);
    r.get(h.columns);
    r.get(type);
    r.get(bitsStored);
    r.get(h.position);
    r.get(h.orientation);
    r.get(h.pixelSpacing);
    r.get(h.sliceSpacing);
    r.get(h.instanceNumber);
    r.get(h.slope);
    r.get(h.intercept);
    r.get(h.problem);
    h.pixelType = FileScalar(type);
    h.bitsStored = bitsStored;
    return h;
}

}  // namespace vdiso
