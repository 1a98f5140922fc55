// 8-bit RGBA images and PNG files.
//
// RgbaImage holds width * height * 4 bytes, R G B A per pixel, rows top first (the pixel
// convention of core/camera.h). Reading converts any PNG (grey, palette, 16-bit, with or
// without alpha) to that form. Both functions are reentrant; errors throw IoError naming the file.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace vdiso {

struct RgbaImage {
    int width = 0;
    int height = 0;
    std::vector<uint8_t> rgba;  // width * height * 4 bytes, top row first

    RgbaImage() = default;
    RgbaImage(int w, int h) : width(w), height(h), rgba(size_t(w) * size_t(h) * 4, 0) {}
    uint8_t* pixel(int x, int y) { return &rgba[(size_t(y) * size_t(width) + size_t(x)) * 4]; }
    const uint8_t* pixel(int x, int y) const {
        return &rgba[(size_t(y) * size_t(width) + size_t(x)) * 4];
    }
};

// Writes `image` as an 8-bit RGBA PNG, atomically (io/atomic_output.h): the file appears
// complete or not at all, and an existing file is replaced only if `overwrite`.
// Throws std::invalid_argument if the image is empty or rgba has the wrong size.
void writePng(const std::string& path, const RgbaImage& image, bool overwrite);

// Throws IoError for a missing or unreadable file, "not a PNG file", or a damaged or
// truncated one.
RgbaImage readPng(const std::string& path);

}  // namespace vdiso
