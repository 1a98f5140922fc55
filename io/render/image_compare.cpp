#include "io/render/image_compare.h"

#include <cstdlib>
#include <map>
#include <stdexcept>

namespace vdiso {

namespace {

uint32_t rgbOf(const RgbaImage& image, int x, int y) {
    const uint8_t* p = &image.rgba[(size_t(y) * size_t(image.width) + size_t(x)) * 4];
    return uint32_t(p[0]) | uint32_t(p[1]) << 8 | uint32_t(p[2]) << 16;
}

uint32_t borderBackground(const RgbaImage& image) {
    std::map<uint32_t, int> counts;
    for (int x = 0; x < image.width; ++x) {
        ++counts[rgbOf(image, x, 0)];
        ++counts[rgbOf(image, x, image.height - 1)];
    }
    for (int y = 0; y < image.height; ++y) {
        ++counts[rgbOf(image, 0, y)];
        ++counts[rgbOf(image, image.width - 1, y)];
    }
    uint32_t best = 0;
    int bestCount = -1;
    for (const auto& [colour, count] : counts)
        if (count > bestCount) best = colour, bestCount = count;
    return best;
}

int maxChannelDifference(uint32_t a, uint32_t b) {
    int d = 0;
    for (int shift = 0; shift < 24; shift += 8)
        d = std::max(d, std::abs(int((a >> shift) & 0xff) - int((b >> shift) & 0xff)));
    return d;
}

}  // namespace

ImageAgreement compareImages(const RgbaImage& reference, const RgbaImage& other, int tolerance) {
    if (reference.width != other.width || reference.height != other.height)
        throw std::invalid_argument("images differ in size: " + std::to_string(reference.width) +
                                    "x" + std::to_string(reference.height) + " and " +
                                    std::to_string(other.width) + "x" +
                                    std::to_string(other.height));
    ImageAgreement a;
    if (reference.width == 0 || reference.height == 0) return a;
    const uint32_t background = borderBackground(reference);
    for (int y = 0; y < reference.height; ++y)
        for (int x = 0; x < reference.width; ++x) {
            const uint32_t r = rgbOf(reference, x, y), o = rgbOf(other, x, y);
            const bool referenceCovers = r != background, otherCovers = o != background;
            if (!referenceCovers) {
                a.extra += otherCovers;
                continue;
            }
            ++a.referenceCovered;
            if (!otherCovers)
                ++a.missing;
            else if (maxChannelDifference(r, o) > tolerance)
                ++a.differentColour;
            else
                ++a.agreeing;
        }
    return a;
}

}  // namespace vdiso
