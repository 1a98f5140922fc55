#include "io/render/png_image.h"

#include <cstring>
#include <stdexcept>

#include <png.h>

#include "io/atomic_output.h"
#include "io/error.h"
#include "io/text_file.h"

namespace vdiso {

namespace {

// A bound on what readPng allocates, so that a forged header cannot ask for terabytes.
constexpr uint64_t kMaxReadPixels = uint64_t(1) << 28;

// libpng's simplified API keeps its state behind png_image::opaque; this frees it on every path.
struct PngImageGuard {
    png_image image;
    PngImageGuard() {
        std::memset(&image, 0, sizeof image);
        image.version = PNG_IMAGE_VERSION;
    }
    ~PngImageGuard() { png_image_free(&image); }
    PngImageGuard(const PngImageGuard&) = delete;
    PngImageGuard& operator=(const PngImageGuard&) = delete;
};

// The largest PNG file read: vdiso's own pictures (at most 8192 x 8192) are far smaller, and an
// endless file is refused after this much.
constexpr size_t kMaxPngBytes = size_t(256) << 20;

std::vector<uint8_t> readBytes(const std::string& path) {
    // Through the bounded reader: a directory, a device or an endless file gets a message that
    // names it, never a stream library's own.
    const std::string text = readBoundedText(path, kMaxPngBytes, "PNG file");
    return std::vector<uint8_t>(text.begin(), text.end());
}

}  // namespace

void writePng(const std::string& path, const RgbaImage& image, bool overwrite) {
    if (image.width <= 0 || image.height <= 0 ||
        image.rgba.size() != size_t(image.width) * size_t(image.height) * 4)
        throw std::invalid_argument("writePng: image is " + std::to_string(image.width) + "x" +
                                    std::to_string(image.height) + " but holds " +
                                    std::to_string(image.rgba.size()) + " bytes");
    // Refuse an existing file before spending time on compression.
    AtomicOutputFile out(path, overwrite);

    PngImageGuard png;
    png.image.width = png_uint_32(image.width);
    png.image.height = png_uint_32(image.height);
    png.image.format = PNG_FORMAT_RGBA;
    png_alloc_size_t size = PNG_IMAGE_PNG_SIZE_MAX(png.image);
    std::vector<uint8_t> encoded(size);
    if (!png_image_write_to_memory(&png.image, encoded.data(), &size, 0, image.rgba.data(),
                                   png_int_32(image.width) * 4, nullptr))
        throwIoError(path, std::string("cannot encode PNG: ") + png.image.message);
    out.append(encoded.data(), size);
    out.commit();
}

RgbaImage readPng(const std::string& path) {
    const std::vector<uint8_t> bytes = readBytes(path);
    if (bytes.size() < 8 || png_sig_cmp(bytes.data(), 0, 8) != 0)
        throwIoError(path, "not a PNG file");

    PngImageGuard png;
    if (!png_image_begin_read_from_memory(&png.image, bytes.data(), bytes.size()))
        throwIoError(path, std::string("damaged PNG: ") + png.image.message);
    if (uint64_t(png.image.width) * png.image.height > kMaxReadPixels)
        throwIoError(path, "PNG too large (" + std::to_string(png.image.width) + "x" +
                               std::to_string(png.image.height) + ")");
    png.image.format = PNG_FORMAT_RGBA;

    RgbaImage image(int(png.image.width), int(png.image.height));
    // Without a background, the conversion keeps alpha instead of compositing.
    if (!png_image_finish_read(&png.image, nullptr, image.rgba.data(),
                               png_int_32(image.width) * 4, nullptr))
        throwIoError(path, std::string("damaged or truncated PNG: ") + png.image.message);
    return image;
}

}  // namespace vdiso
