#include "io/readers/tiff_reader.h"

#include <tiffio.h>

#include <algorithm>
#include <cmath>
#include <cstdarg>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <optional>
#include <string_view>
#include <utility>

#include "core/interrupt.h"
#include "io/error.h"
#include "io/readers/file_list.h"
#include "io/readers/sample_decode.h"

namespace vdiso {
namespace {

// A TIFF opened for reading whose libtiff errors are kept, not printed: the message of the last
// one goes into the IoError of whatever failed.
class TiffHandle {
public:
    explicit TiffHandle(std::string path) : mPath(std::move(path)) {
        TIFFOpenOptions* options = TIFFOpenOptionsAlloc();
        if (!options) throwIoError(mPath, "cannot allocate libtiff's open options");
        TIFFOpenOptionsSetErrorHandlerExtR(options, &TiffHandle::onError, this);
        TIFFOpenOptionsSetWarningHandlerExtR(options, &TiffHandle::onWarning, nullptr);
        // "m": read, not memory-mapped. libtiff maps the whole file by default, and conversion
        // touches every strip once, so a 2 GiB stack ended with 2.2 GB resident (RssFile: the
        // mapped file) where the slab ring is 0.2 GB; reading each strip into its slice costs
        // the same copy.
        mTif = TIFFOpenExt(mPath.c_str(), "rm", options);
        TIFFOpenOptionsFree(options);
        if (!mTif) fail("cannot be read as TIFF");
    }
    ~TiffHandle() {
        if (mTif) TIFFClose(mTif);
    }
    TiffHandle(const TiffHandle&) = delete;
    TiffHandle& operator=(const TiffHandle&) = delete;

    TIFF* tif() const { return mTif; }
    const std::string& path() const { return mPath; }
    void clearMessage() { mMessage.clear(); }
    bool hasMessage() const { return !mMessage.empty(); }

    // Throws "<path>: <what> (libtiff: <its last message>)".
    [[noreturn]] void fail(const std::string& what) const {
        throwIoError(mPath, mMessage.empty() ? what : what + " (libtiff: " + mMessage + ")");
    }

private:
    static int onError(TIFF*, void* self, const char* module, const char* format, va_list args) {
        char text[512];
        std::vsnprintf(text, sizeof(text), format, args);
        auto* handle = static_cast<TiffHandle*>(self);
        handle->mMessage = module ? std::string(module) + ": " + text : std::string(text);
        return 1;  // handled: libtiff's global handler would print it
    }
    // Unknown private tags (ImageJ's, microscope vendors') are routine; nothing to say.
    static int onWarning(TIFF*, void*, const char*, const char*, va_list) { return 1; }

    std::string mPath;
    std::string mMessage;
    TIFF* mTif = nullptr;
};

// What every page of a stack must share.
struct PageFormat {
    uint32_t width = 0, height = 0;
    FileScalar type = FileScalar::U8;
    bool operator==(const PageFormat&) const = default;
};

struct PageInfo {
    PageFormat format;
    bool reducedResolution = false;
};

// A page of the stack: which file, which directory in it.
struct PageRef {
    uint32_t file = 0;
    tdir_t directory = 0;
};

std::string describeFormat(const PageFormat& f) {
    return std::to_string(f.width) + " x " + std::to_string(f.height) + " " + fileScalarName(f.type);
}

std::optional<FileScalar> tiffSampleType(uint16_t bits, uint16_t format) {
    const bool isUnsigned = format == SAMPLEFORMAT_UINT || format == SAMPLEFORMAT_VOID;
    if (isUnsigned && bits == 8) return FileScalar::U8;
    if (isUnsigned && bits == 16) return FileScalar::U16;
    if (isUnsigned && bits == 32) return FileScalar::U32;
    if (format == SAMPLEFORMAT_INT && bits == 8) return FileScalar::I8;
    if (format == SAMPLEFORMAT_INT && bits == 16) return FileScalar::I16;
    if (format == SAMPLEFORMAT_INT && bits == 32) return FileScalar::I32;
    if (format == SAMPLEFORMAT_IEEEFP && bits == 32) return FileScalar::F32;
    if (format == SAMPLEFORMAT_IEEEFP && bits == 64) return FileScalar::F64;
    return std::nullopt;
}

const char* sampleFormatName(uint16_t format) {
    switch (format) {
        case SAMPLEFORMAT_UINT: return "unsigned integer";
        case SAMPLEFORMAT_INT: return "signed integer";
        case SAMPLEFORMAT_IEEEFP: return "floating point";
        case SAMPLEFORMAT_VOID: return "untyped";
        case SAMPLEFORMAT_COMPLEXINT: return "complex integer";
        case SAMPLEFORMAT_COMPLEXIEEEFP: return "complex floating point";
    }
    return "unknown";
}

// The current directory's page, checked: "<where>" prefixes every message ("page 3: ").
PageInfo describePage(const TiffHandle& t, const std::string& where) {
    TIFF* tif = t.tif();
    PageInfo page;
    uint32_t width = 0, height = 0, depth = 1, subfileType = 0;
    uint16_t samplesPerPixel = 1, bits = 1, format = SAMPLEFORMAT_UINT, photometric = 0;
    uint16_t compression = COMPRESSION_NONE;
    if (!TIFFGetField(tif, TIFFTAG_IMAGEWIDTH, &width) ||
        !TIFFGetField(tif, TIFFTAG_IMAGELENGTH, &height))
        t.fail(where + "has no image width or length");
    TIFFGetFieldDefaulted(tif, TIFFTAG_IMAGEDEPTH, &depth);
    TIFFGetFieldDefaulted(tif, TIFFTAG_SUBFILETYPE, &subfileType);
    TIFFGetFieldDefaulted(tif, TIFFTAG_SAMPLESPERPIXEL, &samplesPerPixel);
    TIFFGetFieldDefaulted(tif, TIFFTAG_BITSPERSAMPLE, &bits);
    TIFFGetFieldDefaulted(tif, TIFFTAG_SAMPLEFORMAT, &format);
    TIFFGetFieldDefaulted(tif, TIFFTAG_COMPRESSION, &compression);
    const bool hasPhotometric = TIFFGetField(tif, TIFFTAG_PHOTOMETRIC, &photometric);
    if (width == 0 || height == 0)
        t.fail(where + "is " + std::to_string(width) + " x " + std::to_string(height) + " pixels");
    if (depth != 1)
        t.fail(where + "is a 3-D image (ImageDepth " + std::to_string(depth) +
               "): only 2-D pages are supported");
    if (samplesPerPixel != 1)
        t.fail(where + "has " + std::to_string(samplesPerPixel) +
               " samples per pixel (colour or several channels): only single-channel pages are "
               "supported");
    if (hasPhotometric && photometric == PHOTOMETRIC_PALETTE)
        t.fail(where + "is a palette image: its samples are colour indices, not values");
    const auto type = tiffSampleType(bits, format);
    if (!type)
        t.fail(where + "has " + std::to_string(bits) + "-bit " + sampleFormatName(format) +
               " samples: supported are 8, 16 and 32-bit integers and 32 and 64-bit floats");
    if (!TIFFIsCODECConfigured(compression))
        t.fail(where + "uses compression " + std::to_string(compression) +
               ", which this libtiff cannot decode");
    page.format = {width, height, *type};
    page.reducedResolution = (subfileType & FILETYPE_REDUCEDIMAGE) != 0;
    return page;
}

// The offset of the directory after the current one as the file states it (0: none), or
// nullopt when the current directory cannot be read that far.
std::optional<uint64_t> statedNextDirectory(const TiffHandle& t) {
    TIFF* tif = t.tif();
    const bool big = TIFFIsBigTIFF(tif), swap = TIFFIsByteSwapped(tif);
    std::ifstream in(t.path(), std::ios::binary);
    auto readNumber = [&](uint64_t offset, size_t size) -> std::optional<uint64_t> {
        unsigned char b[8] = {};
        if (!in.seekg(std::streamoff(offset)) || !in.read(reinterpret_cast<char*>(b), std::streamsize(size)))
            return std::nullopt;
        if (swap) std::reverse(b, b + size);
        uint64_t v = 0;
        for (size_t i = size; i-- > 0;) v = (v << 8) | b[i];  // little-endian after the swap
        return v;
    };
    if (hostIsBigEndian()) return std::nullopt;  // the decoding above assumes little-endian
    const uint64_t at = TIFFCurrentDirOffset(tif);
    const size_t countSize = big ? 8 : 2, entrySize = big ? 20 : 12, offsetSize = big ? 8 : 4;
    const auto count = readNumber(at, countSize);
    if (!count || *count > (uint64_t(1) << 32)) return std::nullopt;
    return readNumber(at + countSize + *count * entrySize, offsetSize);
}

// Reads the next directory; false after the last. A directory that cannot be read is an error,
// also when libtiff only warns: it stops quietly at a next-directory offset past the end of a
// truncated file, which would drop the pages that were there.
bool nextDirectory(TiffHandle& t, const std::string& where) {
    // Asked first: a failed TIFFReadDirectory has moved the current offset on.
    const std::optional<uint64_t> next = statedNextDirectory(t);
    t.clearMessage();
    if (TIFFReadDirectory(t.tif())) return true;
    if (t.hasMessage()) t.fail(where + "cannot be read");
    if (!next || *next != 0)
        t.fail(where + "cannot be read: the file ends or is damaged where its directory is");
    return false;
}

// Memory for one strip or tile: at most this, or the page's own size if larger. A tile or strip
// claiming more is a corrupt header, refused before anything is allocated for it.
constexpr uint64_t kMinChunkBound = uint64_t(64) << 20;

// Decodes the current page into dst (width * height samples of storeType).
class PageDecoder {
public:
    void read(const TiffHandle& t, const std::string& where, const PageFormat& f,
              ScalarType storeType, unsigned char* dst) {
        if (TIFFIsTiled(t.tif()))
            readTiles(t, where, f, storeType, dst);
        else
            readStrips(t, where, f, storeType, dst);
    }

private:
    static uint64_t chunkBound(const PageFormat& f) {
        return std::max(kMinChunkBound, uint64_t(f.width) * f.height * fileScalarSize(f.type));
    }

    void readStrips(const TiffHandle& t, const std::string& where, const PageFormat& f,
                    ScalarType storeType, unsigned char* dst) {
        TIFF* tif = t.tif();
        uint32_t rowsPerStrip = 0;
        TIFFGetFieldDefaulted(tif, TIFFTAG_ROWSPERSTRIP, &rowsPerStrip);
        if (rowsPerStrip == 0 || rowsPerStrip > f.height) rowsPerStrip = f.height;
        const uint64_t strips = (uint64_t(f.height) + rowsPerStrip - 1) / rowsPerStrip;
        if (TIFFNumberOfStrips(tif) != strips)
            t.fail(where + "has " + std::to_string(TIFFNumberOfStrips(tif)) + " strips where " +
                   std::to_string(f.height) + " rows of " + std::to_string(rowsPerStrip) +
                   " per strip need " + std::to_string(strips));
        checkChunksInFile(t, where, false);
        const size_t inSize = fileScalarSize(f.type), outSize = scalarSize(storeType);
        const bool direct = fileScalarOf(storeType) == f.type;
        const uint64_t rowBytes = uint64_t(f.width) * inSize;
        for (uint32_t s = 0; s < strips; ++s) {
            const uint64_t row0 = uint64_t(s) * rowsPerStrip;
            const uint64_t rows = std::min<uint64_t>(rowsPerStrip, f.height - row0);
            const uint64_t bytes = rows * rowBytes;
            unsigned char* out = dst + row0 * f.width * outSize;
            if (!direct) mScratch.resize(bytes);
            void* target = direct ? static_cast<void*>(out) : mScratch.data();
            const tmsize_t n = TIFFReadEncodedStrip(tif, s, target, tmsize_t(bytes));
            if (n != tmsize_t(bytes))
                t.fail(where + "strip " + std::to_string(s) + " of " + std::to_string(strips) +
                       " cannot be decoded" +
                       (n >= 0 ? " (" + std::to_string(n) + " of " + std::to_string(bytes) +
                                     " bytes)"
                               : ""));
            if (!direct)
                decodeSamples(mScratch.data(), f.type, false, size_t(rows * f.width), out,
                              storeType);
        }
    }

    // Every strip or tile must lie inside the file, before libtiff reads one: an offset whose
    // end passes 2^63 made read() fail, and libtiff 4.5.0 took the -1 for a byte count and
    // zeroed memory before its buffer (fuzz_tiff campaign). An offset or count of 0 is an entry
    // the file lacks (libtiff fills missing entries with 0).
    static void checkChunksInFile(const TiffHandle& t, const std::string& where, bool tiled) {
        TIFF* tif = t.tif();
        std::error_code ec;
        const uint64_t fileSize = std::filesystem::file_size(t.path(), ec);
        if (ec) t.fail(where + "cannot be measured: " + ec.message());
        const uint32_t n = tiled ? TIFFNumberOfTiles(tif) : TIFFNumberOfStrips(tif);
        for (uint32_t i = 0; i < n; ++i) {
            const uint64_t off = TIFFGetStrileOffset(tif, i), bytes = TIFFGetStrileByteCount(tif, i);
            if (off == 0 || bytes == 0 || off > fileSize || bytes > fileSize - off)
                t.fail(where + (tiled ? "tile " : "strip ") + std::to_string(i) + " (" + std::to_string(bytes) +
                       " bytes at offset " + std::to_string(off) + ") lies outside the file of " +
                       std::to_string(fileSize) + " bytes");
        }
    }

    void readTiles(const TiffHandle& t, const std::string& where, const PageFormat& f,
                   ScalarType storeType, unsigned char* dst) {
        TIFF* tif = t.tif();
        uint32_t tileWidth = 0, tileHeight = 0;
        if (!TIFFGetField(tif, TIFFTAG_TILEWIDTH, &tileWidth) ||
            !TIFFGetField(tif, TIFFTAG_TILELENGTH, &tileHeight) || tileWidth == 0 ||
            tileHeight == 0)
            t.fail(where + "is tiled but has no tile size");
        const size_t inSize = fileScalarSize(f.type), outSize = scalarSize(storeType);
        // In double first: two 32-bit sizes and a sample size may overflow 64 bits.
        if (double(tileWidth) * double(tileHeight) * double(inSize) > double(chunkBound(f)))
            t.fail(where + "has tiles of " + std::to_string(tileWidth) + " x " +
                   std::to_string(tileHeight) + " pixels, larger than the page allows");
        const uint64_t tileBytes = uint64_t(tileWidth) * tileHeight * inSize;
        if (TIFFTileSize64(tif) != tileBytes)
            t.fail(where + "has tiles of " + std::to_string(TIFFTileSize64(tif)) +
                   " bytes where " + std::to_string(tileWidth) + " x " +
                   std::to_string(tileHeight) + " samples need " + std::to_string(tileBytes));
        mScratch.resize(tileBytes);
        checkChunksInFile(t, where, true);
        for (uint32_t y = 0; y < f.height; y += tileHeight) {
            for (uint32_t x = 0; x < f.width; x += tileWidth) {
                const uint32_t tile = TIFFComputeTile(tif, x, y, 0, 0);
                const tmsize_t n =
                    TIFFReadEncodedTile(tif, tile, mScratch.data(), tmsize_t(tileBytes));
                if (n != tmsize_t(tileBytes))
                    t.fail(where + "tile " + std::to_string(tile) + " (at x " + std::to_string(x) +
                           ", y " + std::to_string(y) + ") cannot be decoded");
                const uint32_t cols = std::min(tileWidth, f.width - x);
                const uint32_t rows = std::min(tileHeight, f.height - y);
                for (uint32_t r = 0; r < rows; ++r)
                    decodeSamples(mScratch.data() + size_t(r) * tileWidth * inSize, f.type, false,
                                  cols, dst + (uint64_t(y + r) * f.width + x) * outSize,
                                  storeType);
                if (y == 0 && x == 0) throwIfInterrupted(t.path());
            }
        }
    }

    std::vector<unsigned char> mScratch;
};

// ImageJ stacks say their voxel size: X/YResolution in pixels per unit, and "spacing=" (the z
// step) in the ImageDescription, which starts with "ImageJ=".
std::optional<glm::dvec3> imageJSpacing(TIFF* tif) {
    const char* description = nullptr;
    if (!TIFFGetField(tif, TIFFTAG_IMAGEDESCRIPTION, &description) || !description) return {};
    const std::string_view text(description);
    if (text.rfind("ImageJ=", 0) != 0) return {};
    glm::dvec3 spacing(1.0);
    float resolution = 0.0f;
    if (TIFFGetField(tif, TIFFTAG_XRESOLUTION, &resolution) && std::isfinite(resolution) &&
        resolution > 0.0f)
        spacing.x = 1.0 / double(resolution);
    if (TIFFGetField(tif, TIFFTAG_YRESOLUTION, &resolution) && std::isfinite(resolution) &&
        resolution > 0.0f)
        spacing.y = 1.0 / double(resolution);
    const size_t at = text.find("\nspacing=");
    if (at != std::string_view::npos) {
        const double z = std::atof(std::string(text.substr(at + 9, 32)).c_str());
        if (std::isfinite(z) && z > 0.0) spacing.z = z;
    }
    return spacing;
}

class TiffSliceReader final : public SliceReader {
public:
    TiffSliceReader(std::string name, std::vector<std::string> files, std::vector<PageRef> pages,
                    const PageFormat& format, const VolumeInfo& info)
        : mName(std::move(name)),
          mFiles(std::move(files)),
          mPages(std::move(pages)),
          mFormat(format),
          mInfo(info) {}

    const VolumeInfo& info() const override { return mInfo; }

    void read(void* dst, int64_t count) override {
        auto* out = static_cast<unsigned char*>(dst);
        const size_t sliceBytes = size_t(mInfo.sliceSamples()) * scalarSize(mInfo.type);
        for (int64_t s = 0; s < count; ++s, ++mNext) {
            if (mNext >= int64_t(mPages.size()))
                throwIoError(mName, "has " + std::to_string(mPages.size()) + " pages, fewer than asked");
            throwIfInterrupted(mName);
            const PageRef& page = mPages[size_t(mNext)];
            TiffHandle& t = moveTo(page);
            const std::string where = pageName(page);
            // Checked at open; checked again, as the files may have changed since.
            if (describePage(t, where).format != mFormat)
                t.fail(where + "is no longer " + describeFormat(mFormat));
            mDecoder.read(t, where, mFormat, mInfo.type, out + size_t(s) * sliceBytes);
        }
    }

    // Pages are counted, not decoded: the next read steps to its page (directories only).
    void skip(int64_t count) override {
        if (count < 0 || count > int64_t(mPages.size()) - mNext)
            throwIoError(mName, "has " + std::to_string(mPages.size()) + " pages, fewer than asked");
        mNext += count;
    }

    std::string name() const override { return mName; }
    std::vector<std::string> files() const override { return mFiles; }

private:
    bool multiPage() const { return mFiles.size() == 1; }
    std::string pageName(const PageRef& page) const {
        return multiPage() ? "page " + std::to_string(page.directory + 1) + ": " : "";
    }

    // Opens the page's file (closing the last) and steps to its directory, forward when it can.
    TiffHandle& moveTo(const PageRef& page) {
        if (!mOpen || mOpenFile != page.file) {
            mOpen.reset();
            mOpen = std::make_unique<TiffHandle>(mFiles[page.file]);
            mOpenFile = page.file;
        }
        TiffHandle& t = *mOpen;
        if (TIFFCurrentDirectory(t.tif()) > page.directory) {
            t.clearMessage();
            if (!TIFFSetDirectory(t.tif(), 0)) t.fail("cannot return to its first page");
        }
        while (TIFFCurrentDirectory(t.tif()) < page.directory)
            if (!nextDirectory(t, pageName(page)))
                t.fail(pageName(page) + "is missing: the file has changed since it was opened");
        return t;
    }

    std::string mName;
    std::vector<std::string> mFiles;
    std::vector<PageRef> mPages;
    PageFormat mFormat;
    VolumeInfo mInfo;
    std::unique_ptr<TiffHandle> mOpen;
    uint32_t mOpenFile = 0;
    int64_t mNext = 0;
    PageDecoder mDecoder;
};

VolumeInfo stackInfo(const std::string& name, const PageFormat& f, size_t pages,
                     const std::optional<glm::dvec3>& spacing) {
    VolumeInfo info;
    info.dims = {int64_t(f.width), int64_t(f.height), int64_t(pages)};
    if (pages < 2)
        throwIoError(name, "holds one slice: a volume needs at least 2 (a multi-page TIFF, or a "
                           "folder or glob of single-page slices)");
    requireVolumeDims(name, info.dims);
    info.type = storeTypeFor(f.type, false);
    if (spacing) info.spacing = *spacing;
    return info;
}

std::unique_ptr<SliceReader> openMultiPage(const std::string& path) {
    TiffHandle t(path);
    std::vector<PageRef> pages;
    std::optional<PageFormat> first;
    const std::optional<glm::dvec3> spacing = imageJSpacing(t.tif());
    tdir_t directory = 0;
    do {
        const std::string where = "page " + std::to_string(directory + 1) + ": ";
        const PageInfo page = describePage(t, where);
        if (!page.reducedResolution) {
            if (!first) first = page.format;
            if (page.format != *first)
                t.fail(where + "is " + describeFormat(page.format) + ", unlike page " +
                       std::to_string(pages.front().directory + 1) + " (" +
                       describeFormat(*first) + "): every page must have the same size and type");
            pages.push_back({0, directory});
        }
        if ((directory & 255) == 255) throwIfInterrupted(path);
        ++directory;
    } while (nextDirectory(t, "page " + std::to_string(directory + 1) + ": "));
    if (!first) t.fail("holds only reduced-resolution pages");
    const VolumeInfo info = stackInfo(path, *first, pages.size(), spacing);
    return std::make_unique<TiffSliceReader>(path, std::vector<std::string>{path}, std::move(pages),
                                             *first, info);
}

// The stack of single-page files `files`, called `name` (the folder or pattern) in messages.
std::unique_ptr<SliceReader> openSliceFiles(const std::string& name,
                                            const std::vector<std::string>& files) {
    std::vector<PageRef> pages;
    PageFormat first;
    std::optional<glm::dvec3> spacing;
    for (uint32_t i = 0; i < files.size(); ++i) {
        TiffHandle t(files[i]);
        throwIfInterrupted(files[i]);
        const PageInfo page = describePage(t, "");
        if (page.reducedResolution) t.fail("holds a reduced-resolution page first");
        if (i == 0) {
            first = page.format;
            spacing = imageJSpacing(t.tif());
        } else if (page.format != first) {
            t.fail("is " + describeFormat(page.format) + ", unlike the first slice " + files[0] +
                   " (" + describeFormat(first) + "): every slice must have the same size and type");
        }
        int fullPages = 1;
        while (nextDirectory(t, ""))
            if (!describePage(t, "").reducedResolution) ++fullPages;
        if (fullPages > 1)
            t.fail("holds " + std::to_string(fullPages) +
                   " pages: the slices of a folder or glob must be single-page files");
        pages.push_back({i, 0});
    }
    const VolumeInfo info = stackInfo(name, first, pages.size(), spacing);
    return std::make_unique<TiffSliceReader>(name, files, std::move(pages), first, info);
}

}  // namespace

bool hasTiffMagic(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    unsigned char b[4] = {};
    if (!in.read(reinterpret_cast<char*>(b), 4)) return false;
    const bool little = b[0] == 'I' && b[1] == 'I' && b[3] == 0 && (b[2] == 42 || b[2] == 43);
    const bool big = b[0] == 'M' && b[1] == 'M' && b[2] == 0 && (b[3] == 42 || b[3] == 43);
    return little || big;
}

std::unique_ptr<SliceReader> openTiffSlices(const std::vector<std::string>& files) {
    if (files.empty()) throw IoError("no TIFF slices given");
    if (files.size() == 1) return openMultiPage(files[0]);
    return openSliceFiles(files[0], files);
}

std::unique_ptr<SliceReader> openTiffVolume(const std::string& path) {
    std::error_code ec;
    if (std::filesystem::is_directory(path, ec)) {
        const std::vector<std::string> files = listFolder(path, {".tif", ".tiff"});
        if (files.empty()) throwIoError(path, "holds no .tif or .tiff files");
        if (files.size() == 1)
            throwIoError(path, "holds one TIFF file: give the file itself for a multi-page TIFF");
        return openSliceFiles(path, files);
    }
    if (isGlobPattern(path) && !std::filesystem::exists(path, ec)) {
        const std::vector<std::string> files = expandGlob(path);
        return files.size() == 1 ? openMultiPage(files[0]) : openSliceFiles(path, files);
    }
    return openMultiPage(path);
}

}  // namespace vdiso
