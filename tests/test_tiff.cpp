// TIFF stacks: multi-page files and BigTIFF, folders and globs of slices in natural order, every
// sample type, strips and tiles, the compressions libtiff writes; each written here with libtiff
// and read back sample for sample. And the stacks it must refuse, by name.
#include <gtest/gtest.h>
#include <tiffio.h>

#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "io/store/brick_store.h"
#include "io/error.h"
#include "io/readers/file_list.h"
#include "io/readers/sample_decode.h"
#include "io/readers/tiff_reader.h"
#include "io/readers/volume_open.h"
#include "tests/reader_test_util.h"
#include "tests/test_util.h"

namespace vdiso {
namespace {

using test::expectIoError;

// A value of `type` for sample i, exact in the type and in its store type.
double tiffValue(FileScalar type, int64_t i) {
    switch (type) {
        case FileScalar::U8: return double((i * 37 + 11) % 256);
        case FileScalar::I8: return double((i * 37 + 11) % 256 - 128);
        case FileScalar::U16: return double((i * 7919) % 65536);
        case FileScalar::I16: return double((i * 7919) % 65536 - 32768);
        case FileScalar::U32: return double((i * 1000003) % 16777216);  // exact as f32
        case FileScalar::I32: return double((i * 1000003) % 16777216 - 8388608);
        case FileScalar::F32: return double(i) * 0.25 - 3.0;
        case FileScalar::F64: return double(i) * 0.5 + 0.125;
    }
    return 0.0;
}

std::vector<double> tiffValues(FileScalar type, const Dims3& d) {
    std::vector<double> v(size_t(d[0] * d[1] * d[2]));
    for (size_t i = 0; i < v.size(); ++i) v[i] = tiffValue(type, int64_t(i));
    return v;
}

void tiffFormatOf(FileScalar type, uint16_t& bits, uint16_t& format) {
    bits = uint16_t(8 * fileScalarSize(type));
    switch (type) {
        case FileScalar::I8:
        case FileScalar::I16:
        case FileScalar::I32: format = SAMPLEFORMAT_INT; break;
        case FileScalar::F32:
        case FileScalar::F64: format = SAMPLEFORMAT_IEEEFP; break;
        default: format = SAMPLEFORMAT_UINT;
    }
}

// How a page is laid out and compressed.
struct PageLayout {
    uint16_t compression = COMPRESSION_NONE;
    uint32_t rowsPerStrip = 2;
    uint32_t tile = 0;  // tile side (a multiple of 16); 0 for strips
    bool predictor = false;
    uint16_t samplesPerPixel = 1;
};

// Writes one page: width x height samples of `type` from `values` (native order: libtiff writes
// the file's byte order itself).
void writePage(TIFF* tif, uint32_t width, uint32_t height, FileScalar type, const double* values,
               const PageLayout& layout, uint32_t page, uint32_t pages) {
    uint16_t bits, format;
    tiffFormatOf(type, bits, format);
    TIFFSetField(tif, TIFFTAG_IMAGEWIDTH, width);
    TIFFSetField(tif, TIFFTAG_IMAGELENGTH, height);
    TIFFSetField(tif, TIFFTAG_BITSPERSAMPLE, bits);
    TIFFSetField(tif, TIFFTAG_SAMPLEFORMAT, format);
    TIFFSetField(tif, TIFFTAG_SAMPLESPERPIXEL, layout.samplesPerPixel);
    TIFFSetField(tif, TIFFTAG_PHOTOMETRIC,
                 layout.samplesPerPixel == 3 ? PHOTOMETRIC_RGB : PHOTOMETRIC_MINISBLACK);
    TIFFSetField(tif, TIFFTAG_PLANARCONFIG, PLANARCONFIG_CONTIG);
    TIFFSetField(tif, TIFFTAG_COMPRESSION, layout.compression);
    if (layout.predictor)
        TIFFSetField(tif, TIFFTAG_PREDICTOR,
                     format == SAMPLEFORMAT_IEEEFP ? PREDICTOR_FLOATINGPOINT : PREDICTOR_HORIZONTAL);
    TIFFSetField(tif, TIFFTAG_SUBFILETYPE, FILETYPE_PAGE);
    TIFFSetField(tif, TIFFTAG_PAGENUMBER, uint16_t(page), uint16_t(pages));
    const size_t size = fileScalarSize(type) * layout.samplesPerPixel;
    // The samples as the file holds them, a row after another.
    std::vector<unsigned char> bytes(size_t(width) * height * size);
    std::vector<double> pixelValues;
    for (size_t i = 0; i < size_t(width) * height; ++i)
        for (uint16_t c = 0; c < layout.samplesPerPixel; ++c)
            pixelValues.push_back(values[i]);
    const std::string encoded = test::encodeSamples(pixelValues, type, hostIsBigEndian());
    std::memcpy(bytes.data(), encoded.data(), bytes.size());
    if (layout.tile == 0) {
        TIFFSetField(tif, TIFFTAG_ROWSPERSTRIP, layout.rowsPerStrip);
        for (uint32_t row = 0, strip = 0; row < height; row += layout.rowsPerStrip, ++strip) {
            const uint32_t rows = std::min(layout.rowsPerStrip, height - row);
            ASSERT_GE(TIFFWriteEncodedStrip(tif, strip, bytes.data() + size_t(row) * width * size,
                                            tmsize_t(size_t(rows) * width * size)),
                      0);
        }
    } else {
        const uint32_t t = layout.tile;
        TIFFSetField(tif, TIFFTAG_TILEWIDTH, t);
        TIFFSetField(tif, TIFFTAG_TILELENGTH, t);
        std::vector<unsigned char> tile(size_t(t) * t * size);
        for (uint32_t y = 0; y < height; y += t)
            for (uint32_t x = 0; x < width; x += t) {
                std::fill(tile.begin(), tile.end(), 0);
                for (uint32_t r = 0; r < t && y + r < height; ++r)
                    std::memcpy(tile.data() + size_t(r) * t * size,
                                bytes.data() + (size_t(y + r) * width + x) * size,
                                size_t(std::min(t, width - x)) * size);
                ASSERT_GE(TIFFWriteEncodedTile(tif, TIFFComputeTile(tif, x, y, 0, 0), tile.data(),
                                               tmsize_t(tile.size())),
                          0);
            }
    }
    ASSERT_TRUE(TIFFWriteDirectory(tif));
}

// A multi-page TIFF of `values` (dims[2] pages); `bigTiff` writes the 64-bit variant.
void writeStack(const std::string& path, const Dims3& d, FileScalar type,
                const std::vector<double>& values, const PageLayout& layout, bool bigTiff = false) {
    std::filesystem::create_directories(std::filesystem::path(path).parent_path());
    TIFF* tif = TIFFOpen(path.c_str(), bigTiff ? "w8" : "w");
    ASSERT_NE(tif, nullptr);
    for (int64_t z = 0; z < d[2]; ++z)
        writePage(tif, uint32_t(d[0]), uint32_t(d[1]), type, values.data() + z * d[0] * d[1],
                  layout, uint32_t(z), uint32_t(d[2]));
    TIFFClose(tif);
}

// One single-page TIFF: the slice z of `values`.
void writeSlice(const std::string& path, const Dims3& d, FileScalar type,
                const std::vector<double>& values, int64_t z, const PageLayout& layout = {}) {
    std::filesystem::create_directories(std::filesystem::path(path).parent_path());
    TIFF* tif = TIFFOpen(path.c_str(), "w");
    ASSERT_NE(tif, nullptr);
    writePage(tif, uint32_t(d[0]), uint32_t(d[1]), type, values.data() + z * d[0] * d[1], layout,
              0, 1);
    TIFFClose(tif);
}

void expectStack(SliceReader& reader, const Dims3& d, FileScalar type,
                 const std::vector<double>& values) {
    EXPECT_EQ(reader.info().dims, d);
    EXPECT_EQ(reader.info().type, storeTypeFor(type, false));
    test::expectValues(reader, values);
}

class TiffTest : public test::ReaderFileTest {};
using TiffReader = TiffTest;
using TiffErrors = TiffTest;

constexpr FileScalar kAllTypes[] = {FileScalar::U8,  FileScalar::I8,  FileScalar::U16,
                                    FileScalar::I16, FileScalar::U32, FileScalar::I32,
                                    FileScalar::F32, FileScalar::F64};

TEST(NaturalOrder, NumbersCompareAsNumbers) {
    EXPECT_TRUE(naturalLess("slice_2.tif", "slice_10.tif"));
    EXPECT_FALSE(naturalLess("slice_10.tif", "slice_2.tif"));
    EXPECT_TRUE(naturalLess("s9", "s0010"));
    EXPECT_TRUE(naturalLess("s010", "s0010"));  // equal numbers: fewer leading zeros first
    EXPECT_TRUE(naturalLess("a", "b"));
    EXPECT_TRUE(naturalLess("img", "img1"));
    EXPECT_TRUE(naturalLess("x99999999999999999999999", "x100000000000000000000000"));
    EXPECT_FALSE(naturalLess("same7", "same7"));
}

TEST_F(TiffReader, MultiPageEveryType) {
    const Dims3 d = test::kDims;
    for (FileScalar type : kAllTypes) {
        SCOPED_TRACE(fileScalarName(type));
        const std::vector<double> values = tiffValues(type, d);
        writeStack(path("stack.tif"), d, type, values, {});
        auto reader = openTiffVolume(path("stack.tif"));
        expectStack(*reader, d, type, values);
        EXPECT_EQ(reader->info().spacing, glm::dvec3(1.0));
    }
}

TEST_F(TiffReader, StripsTilesAndCompressions) {
    // Pages of 37 x 21: 16-pixel tiles leave partial tiles on both edges; 4-row strips a short
    // last strip.
    const Dims3 d{37, 21, 3};
    const uint16_t compressions[] = {COMPRESSION_NONE, COMPRESSION_LZW, COMPRESSION_ADOBE_DEFLATE,
                                     COMPRESSION_PACKBITS, COMPRESSION_ZSTD, COMPRESSION_LZMA};
    for (FileScalar type : {FileScalar::U16, FileScalar::F32, FileScalar::U8}) {
        const std::vector<double> values = tiffValues(type, d);
        for (uint16_t compression : compressions) {
            if (!TIFFIsCODECConfigured(compression)) continue;
            for (uint32_t tile : {0u, 16u}) {
                for (bool predictor : {false, true}) {
                    if (predictor && compression != COMPRESSION_LZW &&
                        compression != COMPRESSION_ADOBE_DEFLATE)
                        continue;
                    SCOPED_TRACE(std::string(fileScalarName(type)) + " compression " +
                                 std::to_string(compression) + (tile ? " tiled" : " strips") +
                                 (predictor ? " predictor" : ""));
                    PageLayout layout;
                    layout.compression = compression;
                    layout.rowsPerStrip = 4;
                    layout.tile = tile;
                    layout.predictor = predictor;
                    writeStack(path("c.tif"), d, type, values, layout);
                    auto reader = openTiffVolume(path("c.tif"));
                    expectStack(*reader, d, type, values);
                }
            }
        }
    }
}

TEST_F(TiffReader, BigTiff) {
    const Dims3 d{19, 6, 5};
    const std::vector<double> values = tiffValues(FileScalar::I16, d);
    PageLayout layout;
    layout.compression = COMPRESSION_ADOBE_DEFLATE;
    writeStack(path("big.tif"), d, FileScalar::I16, values, layout, true);
    EXPECT_TRUE(hasTiffMagic(path("big.tif")));
    auto reader = openTiffVolume(path("big.tif"));
    expectStack(*reader, d, FileScalar::I16, values);
}

// The file is read, not memory-mapped: libtiff maps it by default, which made converting a
// 2 GiB stack hold the whole file resident (bench/log.md, "Readers").
TEST_F(TiffReader, DoesNotMapTheFile) {
    const Dims3 d = test::kDims;
    const std::vector<double> values = tiffValues(FileScalar::U16, d);
    writeStack(path("mapped.tif"), d, FileScalar::U16, values, {});
    auto reader = openTiffVolume(path("mapped.tif"));
    std::vector<uint16_t> slice(size_t(d[0] * d[1]));
    reader->read(slice.data(), 1);
    std::ifstream maps("/proc/self/maps");
    ASSERT_TRUE(maps.good());
    for (std::string line; std::getline(maps, line);)
        EXPECT_EQ(line.find("mapped.tif"), std::string::npos) << line;
}

TEST_F(TiffReader, FolderAndGlobInNaturalOrder) {
    // 11 slices named slice_0 ... slice_10: string order would put slice_10 third.
    const Dims3 d{6, 4, 11};
    const std::vector<double> values = tiffValues(FileScalar::U16, d);
    for (int64_t z = 0; z < d[2]; ++z)
        writeSlice(path("slices/slice_" + std::to_string(z) + ".tif"), d, FileScalar::U16, values,
                   z);
    test::writeFile(path("slices/notes.txt"), "not a slice");
    test::writeFile(path("slices/.hidden.tif"), "not a slice either");
    auto folder = openTiffVolume(path("slices"));
    EXPECT_EQ(folder->name(), path("slices"));
    EXPECT_EQ(folder->files().size(), 11u);
    expectStack(*folder, d, FileScalar::U16, values);
    auto glob = openTiffVolume(path("slices/slice_*.tif"));
    expectStack(*glob, d, FileScalar::U16, values);
    // And through volume_open, by what the folder holds and by the pattern.
    EXPECT_EQ(detectInputFormat(path("slices"), {}), InputFormat::Tiff);
    EXPECT_EQ(detectInputFormat(path("slices/slice_?.tif"), {}), InputFormat::Tiff);
    auto opened = openVolume(path("slices"), {});
    expectStack(*opened, d, FileScalar::U16, values);
}

TEST_F(TiffReader, ReducedResolutionPagesAreSkipped) {
    const Dims3 d{8, 6, 3};
    const std::vector<double> values = tiffValues(FileScalar::U8, d);
    TIFF* tif = TIFFOpen(path("preview.tif").c_str(), "w");
    ASSERT_NE(tif, nullptr);
    for (int64_t z = 0; z < d[2]; ++z) {
        writePage(tif, 8, 6, FileScalar::U8, values.data() + z * 48, {}, uint32_t(z), 3);
        // A 4 x 3 preview after each page, as some scanners write.
        TIFFSetField(tif, TIFFTAG_SUBFILETYPE, FILETYPE_REDUCEDIMAGE);
        std::vector<double> small(12, 1.0);
        TIFFSetField(tif, TIFFTAG_IMAGEWIDTH, 4u);
        TIFFSetField(tif, TIFFTAG_IMAGELENGTH, 3u);
        TIFFSetField(tif, TIFFTAG_BITSPERSAMPLE, uint16_t(8));
        TIFFSetField(tif, TIFFTAG_SAMPLESPERPIXEL, uint16_t(1));
        TIFFSetField(tif, TIFFTAG_PHOTOMETRIC, PHOTOMETRIC_MINISBLACK);
        TIFFSetField(tif, TIFFTAG_ROWSPERSTRIP, 3u);
        unsigned char bytes[12] = {};
        ASSERT_GE(TIFFWriteEncodedStrip(tif, 0, bytes, 12), 0);
        ASSERT_TRUE(TIFFWriteDirectory(tif));
    }
    TIFFClose(tif);
    auto reader = openTiffVolume(path("preview.tif"));
    expectStack(*reader, d, FileScalar::U8, values);
}

TEST_F(TiffReader, ImageJSpacingAndSpacingOption) {
    const Dims3 d{5, 4, 3};
    const std::vector<double> values = tiffValues(FileScalar::U8, d);
    TIFF* tif = TIFFOpen(path("ij.tif").c_str(), "w");
    ASSERT_NE(tif, nullptr);
    for (int64_t z = 0; z < d[2]; ++z) {
        TIFFSetField(tif, TIFFTAG_IMAGEDESCRIPTION,
                     "ImageJ=1.54f\nimages=3\nslices=3\nunit=micron\nspacing=2.5\nloop=false\n");
        TIFFSetField(tif, TIFFTAG_XRESOLUTION, 4.0f);  // pixels per micron
        TIFFSetField(tif, TIFFTAG_YRESOLUTION, 2.0f);
        TIFFSetField(tif, TIFFTAG_RESOLUTIONUNIT, RESUNIT_NONE);
        writePage(tif, 5, 4, FileScalar::U8, values.data() + z * 20, {}, uint32_t(z), 3);
    }
    TIFFClose(tif);
    EXPECT_EQ(openTiffVolume(path("ij.tif"))->info().spacing, glm::dvec3(0.25, 0.5, 2.5));
    InputOptions options;
    options.spacing = glm::dvec3(0.1, 0.2, 0.3);
    auto reader = openVolume(path("ij.tif"), options);
    EXPECT_EQ(reader->info().spacing, glm::dvec3(0.1, 0.2, 0.3));
    test::expectValues(*reader, values);
}

TEST_F(TiffReader, ConvertsFromTheCommandLine) {
    const Dims3 d{20, 18, 17};
    const std::vector<double> values = tiffValues(FileScalar::U16, d);
    PageLayout layout;
    layout.compression = COMPRESSION_LZW;
    layout.tile = 16;
    writeStack(path("ct.tif"), d, FileScalar::U16, values, layout);
    const auto r = test::runVdiso("convert " + path("ct.tif") + " " + path("ct.vdiso") +
                                  " --brick 8 --spacing 0.5,0.5,2 --quiet");
    ASSERT_EQ(r.exitCode, 0) << r.output;
    const BrickStoreReader store(path("ct.vdiso"));
    EXPECT_EQ(store.volume().spacing, glm::dvec3(0.5, 0.5, 2.0));
    const std::string samples = test::encodeSamples(values, FileScalar::U16, false);
    EXPECT_EQ(test::compareStoreWithSamples(
                  store, std::vector<unsigned char>(samples.begin(), samples.end())),
              "");
}

TEST_F(TiffErrors, PagesOfDifferentSizes) {
    TIFF* tif = TIFFOpen(path("mixed.tif").c_str(), "w");
    ASSERT_NE(tif, nullptr);
    const std::vector<double> values(100, 7.0);
    writePage(tif, 8, 6, FileScalar::U8, values.data(), {}, 0, 3);
    writePage(tif, 8, 6, FileScalar::U8, values.data(), {}, 1, 3);
    writePage(tif, 8, 7, FileScalar::U8, values.data(), {}, 2, 3);
    writePage(tif, 8, 6, FileScalar::U16, values.data(), {}, 2, 3);
    TIFFClose(tif);
    expectIoError([&] { openTiffVolume(path("mixed.tif")); },
                  {path("mixed.tif"), "page 3", "8 x 7 uint8", "unlike page 1", "8 x 6 uint8"});
}

TEST_F(TiffErrors, PagesOfDifferentTypes) {
    TIFF* tif = TIFFOpen(path("types.tif").c_str(), "w");
    ASSERT_NE(tif, nullptr);
    const std::vector<double> values(48, 7.0);
    writePage(tif, 8, 6, FileScalar::U8, values.data(), {}, 0, 2);
    writePage(tif, 8, 6, FileScalar::U16, values.data(), {}, 1, 2);
    TIFFClose(tif);
    expectIoError([&] { openTiffVolume(path("types.tif")); }, {"page 2", "8 x 6 uint16"});
}

TEST_F(TiffErrors, SlicesOfDifferentSizesAndMultiPageSlices) {
    const Dims3 d{6, 4, 3};
    const std::vector<double> values = tiffValues(FileScalar::U8, d);
    writeSlice(path("a/s1.tif"), d, FileScalar::U8, values, 0);
    writeSlice(path("a/s2.tif"), d, FileScalar::U8, values, 1);
    writeSlice(path("a/s3.tif"), {6, 5, 3}, FileScalar::U8, tiffValues(FileScalar::U8, {6, 5, 3}), 0);
    expectIoError([&] { openTiffVolume(path("a")); },
                  {path("a/s3.tif"), "6 x 5 uint8", "unlike the first slice", path("a/s1.tif")});
    writeSlice(path("b/s1.tif"), d, FileScalar::U8, values, 0);
    writeStack(path("b/s2.tif"), d, FileScalar::U8, values, {});
    expectIoError([&] { openTiffVolume(path("b")); }, {path("b/s2.tif"), "holds 3 pages"});
}

TEST_F(TiffErrors, UnsupportedPagesAndInputs) {
    PageLayout rgb;
    rgb.samplesPerPixel = 3;
    writeStack(path("rgb.tif"), {4, 4, 2}, FileScalar::U8, std::vector<double>(32, 1.0), rgb);
    expectIoError([&] { openTiffVolume(path("rgb.tif")); },
                  {path("rgb.tif"), "page 1", "3 samples per pixel"});
    writeStack(path("one.tif"), {4, 4, 1}, FileScalar::U8, std::vector<double>(16, 1.0), {});
    expectIoError([&] { openTiffVolume(path("one.tif")); }, {path("one.tif"), "one slice"});
    std::filesystem::create_directories(path("empty"));
    expectIoError([&] { openTiffVolume(path("empty")); }, {path("empty"), "no .tif"});
    expectIoError([&] { openTiffVolume(path("none_*.tif")); }, {"none_*.tif", "no file matches"});
    test::writeFile(path("text.tif"), "this is not a TIFF file at all");
    expectIoError([&] { openTiffVolume(path("text.tif")); }, {path("text.tif"), "TIFF"});
    expectIoError([&] { openTiffVolume(path("missing.tif")); }, {path("missing.tif")});
}

// A tile or strip whose offset and count point outside the file is refused by name before
// libtiff reads it: an end past 2^63 made libtiff 4.5.0 zero memory before its buffer (found by
// fuzz_tiff). The BigTIFF's second page has one tile, its offset and count inline in the IFD.
TEST_F(TiffErrors, ChunksOutsideTheFile) {
    const Dims3 d{16, 16, 2};
    const std::vector<double> values = tiffValues(FileScalar::U8, d);
    for (uint32_t tile : {0u, 16u}) {
        SCOPED_TRACE(tile ? "tiled" : "strips");
        PageLayout layout;
        layout.compression = COMPRESSION_LZW;
        layout.tile = tile;
        layout.rowsPerStrip = 16;
        writeStack(path("s.tif"), d, FileScalar::U8, values, layout, true);
        const std::vector<unsigned char> bytes = test::readFile(path("s.tif"));
        auto u64 = [&](size_t at) {
            uint64_t v = 0;
            std::memcpy(&v, bytes.data() + at, 8);
            return v;
        };
        ASSERT_FALSE(hostIsBigEndian());
        // BigTIFF: the first IFD's offset at 8; an IFD is a 64-bit count, 20-byte entries
        // (tag, type, count, value) and the next IFD's offset.
        const uint64_t first = u64(8);
        const uint64_t second = u64(first + 8 + u64(first) * 20);
        const uint16_t offsetTag = tile ? TIFFTAG_TILEOFFSETS : TIFFTAG_STRIPOFFSETS;
        const uint16_t countTag = tile ? TIFFTAG_TILEBYTECOUNTS : TIFFTAG_STRIPBYTECOUNTS;
        size_t offsetAt = 0, countAt = 0;
        for (uint64_t e = 0; e < u64(second); ++e) {
            const size_t at = size_t(second + 8 + e * 20);
            uint16_t tag = 0;
            std::memcpy(&tag, bytes.data() + at, 2);
            if (tag == offsetTag) offsetAt = at + 12;
            if (tag == countTag) countAt = at + 12;
        }
        ASSERT_NE(offsetAt, 0u);
        ASSERT_NE(countAt, 0u);
        const uint64_t count = u64(countAt);
        struct Case { uint64_t offset, count; };
        // (A count of 0 libtiff may estimate itself, for one strip: that is not tried here.)
        for (const Case c : {Case{uint64_t(INT64_MAX) - 16, count}, Case{bytes.size() - 4, count},
                             Case{0, count}}) {
            SCOPED_TRACE(std::to_string(c.offset) + " " + std::to_string(c.count));
            std::vector<unsigned char> b = bytes;
            std::memcpy(b.data() + offsetAt, &c.offset, 8);
            std::memcpy(b.data() + countAt, &c.count, 8);
            test::writeFile(path("bad.tif"), b.data(), b.size());
            expectIoError([&] { test::readAllValues(*openTiffVolume(path("bad.tif"))); },
                          {path("bad.tif"), "page 2", tile ? "tile 0" : "strip 0",
                           "lies outside the file"});
        }
    }
}

// Every truncation of a small stack is refused by name, or gives the very same volume (when
// what it cut holds nothing a sample depends on); every flipped byte either reads or is refused
// by name, never anything else.
TEST_F(TiffErrors, EveryTruncationAndFlippedByte) {
    const Dims3 d{7, 5, 3};
    const std::vector<double> values = tiffValues(FileScalar::U16, d);
    for (uint32_t tile : {0u, 16u}) {
        SCOPED_TRACE(tile ? "tiled" : "strips");
        PageLayout layout;
        layout.compression = COMPRESSION_ADOBE_DEFLATE;
        layout.tile = tile;
        writeStack(path("s.tif"), d, FileScalar::U16, values, layout);
        const std::vector<unsigned char> bytes = test::readFile(path("s.tif"));
        // A flipped byte may well make a valid stack of other dimensions (a page marked as a
        // preview, a narrower page), so only a truncation must keep them.
        bool wantDims = true;
        auto readAll = [&](const std::vector<unsigned char>& b) {
            test::writeFile(path("bad.tif"), b.data(), b.size());
            auto reader = openTiffVolume(path("bad.tif"));
            if (wantDims) {
                EXPECT_EQ(reader->info().dims, d);
            }
            return test::readAllValues(*reader);
        };
        for (size_t n = 0; n < bytes.size(); ++n) {
            SCOPED_TRACE(n);
            try {
                EXPECT_EQ(readAll(std::vector<unsigned char>(bytes.begin(), bytes.begin() + n)),
                          values);
            } catch (const IoError& e) {
                EXPECT_NE(std::string(e.what()).find(path("bad.tif")), std::string::npos)
                    << e.what();
            }
        }
        wantDims = false;
        for (size_t i = 0; i < bytes.size(); ++i) {
            std::vector<unsigned char> b = bytes;
            b[i] ^= 0xff;
            try {
                readAll(b);
            } catch (const IoError& e) {
                EXPECT_NE(std::string(e.what()).find(path("bad.tif")), std::string::npos)
                    << e.what();
            } catch (const std::exception& e) {
                ADD_FAILURE() << "byte " << i << ": not an IoError: " << e.what();
            }
        }
    }
}

TEST_F(TiffReader, SkipCountsPagesAndSliceFiles) {
    const Dims3 d = test::kDims;
    const std::vector<double> values = tiffValues(FileScalar::U16, d);
    writeStack(path("stack.tif"), d, FileScalar::U16, values, {});
    test::expectSkipMatchesRead([&] { return openTiffVolume(path("stack.tif")); });
    for (int64_t z = 0; z < d[2]; ++z)
        writeSlice(path("slices/s" + std::to_string(z) + ".tif"), d, FileScalar::U16, values, z);
    test::expectSkipMatchesRead([&] { return openTiffVolume(path("slices")); });
}

}  // namespace
}  // namespace vdiso
