// A multi-page TIFF written with libtiff, a page at a time, as tests/test_tiff.cpp writes its
// small ones.
#include <tiffio.h>

#include <algorithm>
#include <memory>
#include <stdexcept>
#include <vector>

#include "bench/inputs/writers.h"

namespace vdiso::bench {

void writeTiffStack(const HeadSlices& head, const std::string& path, bool deflate) {
    const auto n = uint32_t(head.size());
    if (uint64_t(n) * n * n * 2 >= (uint64_t(1) << 32) - (uint64_t(1) << 26))
        throw std::runtime_error(path + ": a head of " + std::to_string(n) +
                                 "^3 does not fit a classic TIFF");
    std::unique_ptr<TIFF, void (*)(TIFF*)> tif(TIFFOpen(path.c_str(), "w"), TIFFClose);
    if (!tif) throw std::runtime_error(path + ": libtiff cannot create it");
    std::vector<uint16_t> page(size_t(n) * n);
    for (uint32_t z = 0; z < n; ++z) {
        head.read(z, 1, page.data());
        TIFF* t = tif.get();
        TIFFSetField(t, TIFFTAG_IMAGEWIDTH, n);
        TIFFSetField(t, TIFFTAG_IMAGELENGTH, n);
        TIFFSetField(t, TIFFTAG_BITSPERSAMPLE, uint16_t(16));
        TIFFSetField(t, TIFFTAG_SAMPLEFORMAT, uint16_t(SAMPLEFORMAT_UINT));
        TIFFSetField(t, TIFFTAG_SAMPLESPERPIXEL, uint16_t(1));
        TIFFSetField(t, TIFFTAG_PHOTOMETRIC, uint16_t(PHOTOMETRIC_MINISBLACK));
        TIFFSetField(t, TIFFTAG_PLANARCONFIG, uint16_t(PLANARCONFIG_CONTIG));
        TIFFSetField(t, TIFFTAG_COMPRESSION, uint16_t(deflate ? COMPRESSION_ADOBE_DEFLATE : COMPRESSION_NONE));
        if (deflate) TIFFSetField(t, TIFFTAG_PREDICTOR, uint16_t(PREDICTOR_HORIZONTAL));
        TIFFSetField(t, TIFFTAG_SUBFILETYPE, uint32_t(FILETYPE_PAGE));
        TIFFSetField(t, TIFFTAG_PAGENUMBER, uint16_t(z), uint16_t(n));
        const uint32_t rowsPerStrip = TIFFDefaultStripSize(t, 0);
        TIFFSetField(t, TIFFTAG_ROWSPERSTRIP, rowsPerStrip);
        // The predictor differences the buffer in place: each strip is written once, from the page.
        for (uint32_t row = 0, strip = 0; row < n; row += rowsPerStrip, ++strip) {
            const uint32_t rows = std::min(rowsPerStrip, n - row);
            if (TIFFWriteEncodedStrip(t, strip, page.data() + size_t(row) * n,
                                      tmsize_t(size_t(rows) * n * 2)) < 0)
                throw std::runtime_error(path + ": libtiff cannot write page " + std::to_string(z));
        }
        if (!TIFFWriteDirectory(t))
            throw std::runtime_error(path + ": libtiff cannot write page " + std::to_string(z));
    }
    TIFF* t = tif.release();
    TIFFClose(t);  // flushes; libtiff reports its failures through the error handler only
}

}  // namespace vdiso::bench
