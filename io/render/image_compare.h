// Comparing two renderings of the same view: how much of the reference's surface the other
// reproduces. This is the fidelity measure of view-dependent extraction (docs/design.md, "Correctness contract": a
// view-dependent extraction rendered from its own camera must look like the full surface).
#pragma once

#include <cstdint>

#include "io/render/png_image.h"

namespace vdiso {

struct ImageAgreement {
    uint64_t referenceCovered = 0;  // pixels the reference's surface covers
    uint64_t agreeing = 0;          // of those, covered in the other with a close colour
    uint64_t missing = 0;           // of those, background in the other
    uint64_t differentColour = 0;   // of those, covered but off by more than the tolerance
    uint64_t extra = 0;             // covered in the other only
    double agreement() const {
        return referenceCovered ? double(agreeing) / double(referenceCovered) : 1.0;
    }
};

// The background is the colour most frequent along the reference's border; a pixel is
// covered where it differs from it. Colours agree when no channel differs by more than
// `tolerance` (0-255). Throws std::invalid_argument if the sizes differ.
ImageAgreement compareImages(const RgbaImage& reference, const RgbaImage& other, int tolerance = 24);

}  // namespace vdiso
