// NIfTI-1 reader: .nii, .nii.gz and .hdr/.img pairs, either byte order, every datatype the
// store can hold, scl_slope/scl_inter; and the inputs it must refuse, each with a message that
// names the file and the problem. Headers are written byte by byte at the standard offsets.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <limits>
#include <string>
#include <vector>

#include "io/readers/nifti_reader.h"
#include "io/readers/sample_decode.h"
#include "tests/reader_test_util.h"

namespace vdiso {
namespace {

using test::encodeSamples;
using test::expectDoubleEq;
using test::expectIoError;
using test::expectValues;
using test::gzipBytes;
using test::kDims;
using test::kSamples;
using test::testValues;

void openAndReadAll(const std::string& path) {
    auto reader = openNiftiVolume(path);
    test::readAllValues(*reader);
}

struct NiftiType {
    int16_t code;
    FileScalar type;
};

const NiftiType kNiftiTypes[] = {
    {2, FileScalar::U8},   {4, FileScalar::I16},  {8, FileScalar::I32},   {16, FileScalar::F32},
    {64, FileScalar::F64}, {256, FileScalar::I8}, {512, FileScalar::U16}, {768, FileScalar::U32},
};

// A nifti_1_header, filled in at the offsets of nifti1.h.
class NiftiHeaderBuilder {
public:
    explicit NiftiHeaderBuilder(FileScalar type, int16_t datatype, bool bigEndian = false)
        : mBigEndian(bigEndian) {
        mBytes.fill(0);
        setI32(0, 348);
        const int16_t dims[8] = {3, 7, 5, 4, 1, 1, 1, 1};
        for (int d = 0; d < 8; ++d) setI16(40 + 2 * d, dims[d]);
        setI16(70, datatype);
        setI16(72, int16_t(8 * fileScalarSize(type)));
        const float pixdim[4] = {1.0f, 0.5f, 0.75f, 2.5f};
        for (int d = 0; d < 4; ++d) setF32(76 + 4 * d, pixdim[d]);
        setF32(108, 352.0f);  // vox_offset
        setF32(112, 1.0f);    // scl_slope: 1 with intercept 0 means unscaled
        setI16(252, 1);       // qform_code
        setF32(268, -10.5f);
        setF32(272, 20.0f);
        setF32(276, 3.25f);
        setMagic("n+1");
    }

    NiftiHeaderBuilder& setI16(size_t offset, int16_t v) { return put(offset, v); }
    NiftiHeaderBuilder& setI32(size_t offset, int32_t v) { return put(offset, v); }
    NiftiHeaderBuilder& setF32(size_t offset, float v) { return put(offset, v); }
    NiftiHeaderBuilder& setDim(int index, int16_t v) { return setI16(40 + 2 * size_t(index), v); }
    NiftiHeaderBuilder& setMagic(const char* magic) {
        std::memcpy(mBytes.data() + 344, magic, 4);
        return *this;
    }
    NiftiHeaderBuilder& setScaling(float slope, float intercept) {
        setF32(112, slope);
        return setF32(116, intercept);
    }

    // The header, then vox_offset - 348 bytes (the extension flag, zero: no extensions).
    std::string bytes(size_t voxOffset = 352) const {
        std::string out(reinterpret_cast<const char*>(mBytes.data()), mBytes.size());
        out.resize(voxOffset, '\0');
        return out;
    }

private:
    template <class T>
    NiftiHeaderBuilder& put(size_t offset, T v) {
        unsigned char b[sizeof(T)];
        std::memcpy(b, &v, sizeof(T));
        if (mBigEndian != hostIsBigEndian()) std::reverse(b, b + sizeof(T));
        std::memcpy(mBytes.data() + offset, b, sizeof(T));
        return *this;
    }

    std::array<unsigned char, 348> mBytes;
    bool mBigEndian;
};

class NiftiTest : public test::ReaderFileTest {
protected:
    // A .nii (or, gzipped, .nii.gz) holding the test values of `type`.
    std::string writeNii(const std::string& name, FileScalar type, int16_t code,
                         bool gzip = false) const {
        const std::string bytes =
            NiftiHeaderBuilder(type, code).bytes() + encodeSamples(testValues(type), type, false);
        return write(name, gzip ? gzipBytes(bytes) : bytes);
    }
};

using NiftiReader = NiftiTest;
using NiftiErrors = NiftiTest;

TEST_F(NiftiReader, EveryDatatypeUncompressedAndGzip) {
    for (const NiftiType& t : kNiftiTypes) {
        for (bool gzip : {false, true}) {
            SCOPED_TRACE(std::string(fileScalarName(t.type)) + (gzip ? " gzip" : ""));
            const std::string p = writeNii(gzip ? "vol.nii.gz" : "vol.nii", t.type, t.code, gzip);
            auto reader = openNiftiVolume(p);
            const VolumeInfo& info = reader->info();
            EXPECT_EQ(info.dims, kDims);
            EXPECT_EQ(info.type, storeTypeFor(t.type, false));
            EXPECT_EQ(info.spacing, glm::dvec3(0.5, 0.75, 2.5));
            // qoffset in RAS, the origin in LPS.
            EXPECT_EQ(info.origin, glm::dvec3(10.5, -20.0, 3.25));
            EXPECT_EQ(reader->name(), p);
            expectValues(*reader, testValues(t.type));
        }
    }
}

TEST_F(NiftiReader, GzipDetectedByMagicNotExtension) {
    auto reader = openNiftiVolume(writeNii("misnamed.nii", FileScalar::I16, 4, true));
    expectValues(*reader, testValues(FileScalar::I16));
}

TEST_F(NiftiReader, ByteSwappedHeaderAndSamples) {
    for (const NiftiType& t : kNiftiTypes) {
        SCOPED_TRACE(fileScalarName(t.type));
        const std::string bytes = NiftiHeaderBuilder(t.type, t.code, true).bytes() +
                                  encodeSamples(testValues(t.type), t.type, true);
        auto reader = openNiftiVolume(write("swapped.nii", bytes));
        EXPECT_EQ(reader->info().dims, kDims);
        EXPECT_EQ(reader->info().spacing, glm::dvec3(0.5, 0.75, 2.5));
        EXPECT_EQ(reader->info().origin, glm::dvec3(10.5, -20.0, 3.25));
        expectValues(*reader, testValues(t.type));
        auto gz = openNiftiVolume(write("swapped.nii.gz", gzipBytes(bytes)));
        expectValues(*gz, testValues(t.type));
    }
}

TEST_F(NiftiReader, SlopeAndInterceptGiveFloat) {
    const std::string bytes =
        NiftiHeaderBuilder(FileScalar::I16, 4).setScaling(0.5f, -10.0f).bytes() +
        encodeSamples(testValues(FileScalar::I16), FileScalar::I16, false);
    std::vector<double> want = testValues(FileScalar::I16);
    for (double& v : want) v = double(float(v * 0.5 - 10.0));
    for (const char* name : {"scaled.nii", "scaled.nii.gz"}) {
        SCOPED_TRACE(name);
        const bool gzip = std::string(name).ends_with(".gz");
        auto reader = openNiftiVolume(write(name, gzip ? gzipBytes(bytes) : bytes));
        EXPECT_EQ(reader->info().type, ScalarType::F32);
        expectValues(*reader, want);
    }
    // A slope of 1 with a non-zero intercept is still scaling.
    const std::string shifted =
        NiftiHeaderBuilder(FileScalar::U8, 2).setScaling(1.0f, 1000.0f).bytes() +
        encodeSamples(testValues(FileScalar::U8), FileScalar::U8, false);
    auto reader = openNiftiVolume(write("shifted.nii", shifted));
    EXPECT_EQ(reader->info().type, ScalarType::F32);
    want = testValues(FileScalar::U8);
    for (double& v : want) v += 1000.0;
    expectValues(*reader, want);
}

TEST_F(NiftiReader, IdentityOrZeroSlopeKeepsFileType) {
    // nibabel writes a NaN slope (and intercept) for images it does not scale.
    const float nan = std::numeric_limits<float>::quiet_NaN();
    for (auto [slope, intercept] :
         {std::pair{0.0f, 0.0f}, {0.0f, 5.0f}, {1.0f, 0.0f}, {nan, nan}, {nan, 0.0f}}) {
        SCOPED_TRACE(slope);
        const std::string bytes =
            NiftiHeaderBuilder(FileScalar::U16, 512).setScaling(slope, intercept).bytes() +
            encodeSamples(testValues(FileScalar::U16), FileScalar::U16, false);
        auto reader = openNiftiVolume(write("u16.nii", bytes));
        EXPECT_EQ(reader->info().type, ScalarType::U16);
        expectValues(*reader, testValues(FileScalar::U16));
    }
}

TEST_F(NiftiReader, PixdimSignAndZeroWithoutPlacement) {
    NiftiHeaderBuilder h(FileScalar::U8, 2);
    h.setF32(80, -0.8f).setF32(84, 0.0f).setF32(88, 3.0f);
    // Neither qform nor sform: pixdim's spacing, origin 0, no orientation.
    h.setI16(252, 0).setI16(254, 0);
    auto reader = openNiftiVolume(write(
        "v.nii", h.bytes() + encodeSamples(testValues(FileScalar::U8), FileScalar::U8, false)));
    expectDoubleEq(reader->info().spacing, {double(0.8f), 1.0, 3.0});
    EXPECT_EQ(reader->info().origin, glm::dvec3(0.0));
    EXPECT_FALSE(reader->info().hasOrientation);
    EXPECT_EQ(reader->info().direction, glm::dmat3(1.0));
}

std::string u8Samples() { return encodeSamples(testValues(FileScalar::U8), FileScalar::U8, false); }

// The qform: a quarter turn about z (quaternion d = sin 45 deg) and qfac -1 (the third axis
// flipped), in RAS: i -> (0,1,0), j -> (-1,0,0), k -> (0,0,-1). In LPS x and y change sign.
TEST_F(NiftiReader, QformRotationAndFlipInLps) {
    NiftiHeaderBuilder h(FileScalar::U8, 2);
    h.setF32(76, -1.0f).setF32(264, float(std::sqrt(0.5)));
    h.setI16(254, 0);
    auto reader = openNiftiVolume(write("q.nii", h.bytes() + u8Samples()));
    const VolumeInfo& info = reader->info();
    EXPECT_TRUE(info.hasOrientation);
    test::expectDirection(info.direction, glm::dmat3(0, -1, 0, 1, 0, 0, 0, 0, -1));
    EXPECT_EQ(info.origin, glm::dvec3(10.5, -20.0, 3.25));
    EXPECT_EQ(info.spacing, glm::dvec3(0.5, 0.75, 2.5));
}

// Both forms, as nibabel and ITK (so 3D Slicer) choose: the sform, unless it shears or is
// broken, when the qform (rigid) is taken.
TEST_F(NiftiReader, SformWinsUnlessItShearsOrIsBroken) {
    auto withSform = [&](const std::string& name, const float (&rows)[3][4]) {
        NiftiHeaderBuilder h(FileScalar::U8, 2);
        h.setF32(76, -1.0f).setF32(264, float(std::sqrt(0.5)));  // the qform above
        h.setI16(254, 1);
        for (int r = 0; r < 3; ++r)
            for (int c = 0; c < 4; ++c) h.setF32(280 + 16 * size_t(r) + 4 * size_t(c), rows[r][c]);
        return openNiftiVolume(write(name, h.bytes() + u8Samples()))->info();
    };
    const float scaled[3][4] = {{5, 0, 0, 1}, {0, 5, 0, 2}, {0, 0, 5, 3}};
    VolumeInfo info = withSform("sform.nii", scaled);
    test::expectDirection(info.direction, glm::dmat3(-1, 0, 0, 0, -1, 0, 0, 0, 1));
    expectDoubleEq(info.spacing, {5.0, 5.0, 5.0});
    expectDoubleEq(info.origin, {-1.0, -2.0, 3.0});
    const float sheared[3][4] = {{5, 1, 0, 1}, {0, 5, 0, 2}, {0, 0, 5, 3}};
    info = withSform("sheared.nii", sheared);
    test::expectDirection(info.direction, glm::dmat3(0, -1, 0, 1, 0, 0, 0, 0, -1));
    EXPECT_EQ(info.origin, glm::dvec3(10.5, -20.0, 3.25));
    const float singular[3][4] = {{5, 5, 0, 1}, {0, 0, 0, 2}, {0, 0, 5, 3}};
    info = withSform("singular.nii", singular);
    test::expectDirection(info.direction, glm::dmat3(0, -1, 0, 1, 0, 0, 0, 0, -1));
}

// Only an sform: its columns are the axes' steps in RAS, giving spacing and direction; its
// last column the origin.
TEST_F(NiftiReader, SformOnlyGivesDirectionSpacingAndOrigin) {
    NiftiHeaderBuilder h(FileScalar::U8, 2);
    h.setI16(252, 0).setI16(254, 2);
    const float rows[3][4] = {{0, -0.5f, 0, 1.5f}, {0, 0, 3, -2.5f}, {2, 0, 0, 7}};
    for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 4; ++c) h.setF32(280 + 16 * size_t(r) + 4 * size_t(c), rows[r][c]);
    auto reader = openNiftiVolume(write("s.nii", h.bytes() + u8Samples()));
    const VolumeInfo& info = reader->info();
    EXPECT_TRUE(info.hasOrientation);
    // RAS i (0,0,1), j (-1,0,0), k (0,1,0).
    test::expectDirection(info.direction, glm::dmat3(0, 0, 1, 1, 0, 0, 0, -1, 0));
    expectDoubleEq(info.spacing, {2.0, 0.5, 3.0});
    expectDoubleEq(info.origin, {-1.5, 2.5, 7.0});
}

TEST_F(NiftiErrors, SingularOrNonFinitePlacementIsRefused) {
    const float nan = std::numeric_limits<float>::quiet_NaN();
    {
        NiftiHeaderBuilder h(FileScalar::U8, 2);
        h.setI16(252, 0).setI16(254, 1).setF32(280, 1.0f).setF32(284, 1.0f).setF32(296, 1.0f)
            .setF32(300, 1.0f).setF32(320, 1.0f);  // i and j along the same line
        const std::string p = write("singular.nii", h.bytes() + u8Samples());
        expectIoError([&] { openNiftiVolume(p); }, {p, "sform", "singular"});
    }
    {
        NiftiHeaderBuilder h(FileScalar::U8, 2);
        h.setI16(252, 0).setI16(254, 1).setF32(280, nan).setF32(300, 1.0f).setF32(320, 1.0f);
        const std::string p = write("nan.nii", h.bytes() + u8Samples());
        expectIoError([&] { openNiftiVolume(p); }, {p, "sform", "not finite"});
    }
    {
        NiftiHeaderBuilder h(FileScalar::U8, 2);
        h.setI16(254, 1).setF32(280, 0.0f).setF32(300, 0.0f).setF32(320, 0.0f);  // all zero
        h.setI16(252, 0);
        const std::string p = write("zero.nii", h.bytes() + u8Samples());
        expectIoError([&] { openNiftiVolume(p); }, {p, "sform", "zero vector"});
    }
    {
        NiftiHeaderBuilder h(FileScalar::U8, 2);
        h.setF32(260, nan);
        const std::string p = write("q.nii", h.bytes() + u8Samples());
        expectIoError([&] { openNiftiVolume(p); }, {p, "qform quaternion", "not finite"});
    }
}

TEST_F(NiftiReader, VoxOffsetSkipsExtensions) {
    NiftiHeaderBuilder h(FileScalar::I16, 4);
    h.setF32(108, 448.0f);
    std::string bytes = h.bytes(448);
    // Extension flag 1, then one 96-byte extension (esize, ecode, payload).
    const unsigned char flag[4] = {1, 0, 0, 0};
    std::memcpy(bytes.data() + 348, flag, 4);
    std::memset(bytes.data() + 360, 'E', 88);
    bytes += encodeSamples(testValues(FileScalar::I16), FileScalar::I16, false);
    auto reader = openNiftiVolume(write("ext.nii", bytes));
    expectValues(*reader, testValues(FileScalar::I16));
    auto gz = openNiftiVolume(write("ext.nii.gz", gzipBytes(bytes)));
    expectValues(*gz, testValues(FileScalar::I16));
}

TEST_F(NiftiReader, HeaderImagePair) {
    NiftiHeaderBuilder h(FileScalar::F32, 16);
    h.setMagic("ni1").setF32(108, 0.0f);
    const std::string samples = encodeSamples(testValues(FileScalar::F32), FileScalar::F32, false);
    const std::string hdr = write("pair.hdr", h.bytes(348));
    const std::string img = write("pair.img", samples);
    for (const std::string& p : {hdr, img}) {
        SCOPED_TRACE(p);
        auto reader = openNiftiVolume(p);
        EXPECT_EQ(reader->info().dims, kDims);
        expectValues(*reader, testValues(FileScalar::F32));
    }
    // Names from other systems come in capitals.
    write("UPPER.HDR", h.bytes(348));
    write("UPPER.IMG", samples);
    expectValues(*openNiftiVolume(path("UPPER.HDR")), testValues(FileScalar::F32));
    expectValues(*openNiftiVolume(path("UPPER.IMG")), testValues(FileScalar::F32));
    // Compressed pairs, in either half.
    write("gz.hdr.gz", gzipBytes(h.bytes(348)));
    write("gz.img.gz", gzipBytes(samples));
    auto reader = openNiftiVolume(path("gz.hdr.gz"));
    expectValues(*reader, testValues(FileScalar::F32));
    reader = openNiftiVolume(path("gz.img.gz"));
    expectValues(*reader, testValues(FileScalar::F32));
}

TEST_F(NiftiReader, FourDWithOneFrame) {
    NiftiHeaderBuilder h(FileScalar::U8, 2);
    h.setDim(0, 5).setDim(4, 1).setDim(5, 1);
    auto reader = openNiftiVolume(write(
        "t.nii", h.bytes() + encodeSamples(testValues(FileScalar::U8), FileScalar::U8, false)));
    EXPECT_EQ(reader->info().dims, kDims);
    expectValues(*reader, testValues(FileScalar::U8));
}

TEST_F(NiftiErrors, FourDWithThreeFrames) {
    NiftiHeaderBuilder h(FileScalar::U8, 2);
    h.setDim(0, 4).setDim(4, 3);
    const std::string p = write("frames.nii", h.bytes() + std::string(3 * kSamples, '\0'));
    expectIoError([&] { openNiftiVolume(p); },
                  {p, "has 3 frames; only single 3-D volumes are supported"});
}

TEST_F(NiftiErrors, TwoDimensional) {
    NiftiHeaderBuilder h(FileScalar::U8, 2);
    h.setDim(0, 2).setDim(3, 1);
    const std::string p = write("flat.nii", h.bytes() + std::string(35, '\0'));
    expectIoError([&] { openNiftiVolume(p); }, {p, "only 3-D volumes are supported"});
}

TEST_F(NiftiErrors, UnsupportedDatatypes) {
    for (int16_t code : {1, 32, 128, 1024, 1280, 1536, 1792, 2048, 2304, 3}) {
        const std::string p = write("c.nii", NiftiHeaderBuilder(FileScalar::U8, code).bytes() +
                                                 std::string(kSamples * 8, '\0'));
        expectIoError([&] { openNiftiVolume(p); },
                      {p, "unsupported NIfTI datatype " + std::to_string(code)});
    }
}

TEST_F(NiftiErrors, Nifti2Refused) {
    for (bool bigEndian : {false, true}) {
        NiftiHeaderBuilder h(FileScalar::U8, 2, bigEndian);
        h.setI32(0, 540).setMagic("n+2");
        const std::string p = write("two.nii", h.bytes(560) + std::string(kSamples, '\0'));
        expectIoError([&] { openNiftiVolume(p); }, {p, "NIfTI-2 is not supported"});
    }
}

TEST_F(NiftiErrors, BadMagicAndNotNifti) {
    NiftiHeaderBuilder h(FileScalar::U8, 2);
    h.setMagic("abc");
    const std::string magic = write("magic.nii", h.bytes() + std::string(kSamples, '\0'));
    expectIoError([&] { openNiftiVolume(magic); }, {magic, "not a NIfTI-1 file", "magic"});
    const std::string text = write("text.nii", std::string(400, 'x'));
    expectIoError([&] { openNiftiVolume(text); }, {text, "not a NIfTI-1 file", "sizeof_hdr"});
    const std::string tiny = write("tiny.nii", std::string("\x5c\x01\0\0", 4) + "ab");
    expectIoError([&] { openNiftiVolume(tiny); }, {tiny, "ends after 6 bytes", "348-byte"});
    const std::string empty = write("empty.nii", "");
    expectIoError([&] { openNiftiVolume(empty); }, {empty, "not a NIfTI-1 file"});
    expectIoError([&] { openNiftiVolume(path("absent.nii")); }, {"absent.nii", "cannot open"});
}

TEST_F(NiftiErrors, DataShorterAndLonger) {
    const std::string full = NiftiHeaderBuilder(FileScalar::I16, 4).bytes() +
                             encodeSamples(testValues(FileScalar::I16), FileScalar::I16, false);
    const std::string shorter = write("short.nii", full.substr(0, full.size() - 6));
    expectIoError([&] { openNiftiVolume(shorter); }, {shorter, "6 bytes shorter"});
    const std::string longer = write("long.nii", full + "xyz");
    expectIoError([&] { openNiftiVolume(longer); }, {longer, "3 bytes longer"});
    const std::string gzShort = write("short.nii.gz", gzipBytes(full.substr(0, full.size() - 6)));
    expectIoError([&] { openAndReadAll(gzShort); }, {gzShort, "ends after"});
    const std::string gzLong = write("long.nii.gz", gzipBytes(full + "xyz"));
    expectIoError([&] { openAndReadAll(gzLong); }, {gzLong, "holds more data"});
}

TEST_F(NiftiErrors, CorruptGzip) {
    std::string gz =
        gzipBytes(NiftiHeaderBuilder(FileScalar::U16, 512).bytes() +
                  encodeSamples(test::incompressibleU16Values(), FileScalar::U16, false));
    for (size_t i = gz.size() / 2 - 4; i < gz.size() / 2 + 4; ++i) gz[i] = char(~gz[i]);
    const std::string p = write("corrupt.nii.gz", gz);
    expectIoError([&] { openAndReadAll(p); }, {p, "corrupt gzip data"});
}

TEST_F(NiftiErrors, TruncatedGzip) {
    std::string gz = gzipBytes(NiftiHeaderBuilder(FileScalar::F64, 64).bytes() +
                               encodeSamples(testValues(FileScalar::F64), FileScalar::F64, false));
    gz.resize(gz.size() * 3 / 4);
    const std::string p = write("trunc.nii.gz", gz);
    expectIoError([&] { openAndReadAll(p); }, {p, "truncated"});
}

TEST_F(NiftiErrors, NonFiniteScaling) {
    for (float slope :
         {std::numeric_limits<float>::infinity(), -std::numeric_limits<float>::infinity()}) {
        const std::string p =
            write("inf.nii", NiftiHeaderBuilder(FileScalar::U8, 2).setScaling(slope, 0.0f).bytes() +
                                 std::string(kSamples, '\0'));
        expectIoError([&] { openNiftiVolume(p); }, {p, "scl_slope"});
    }
    const std::string p =
        write("nan.nii", NiftiHeaderBuilder(FileScalar::U8, 2).setScaling(2.0f, NAN).bytes() +
                             std::string(kSamples, '\0'));
    expectIoError([&] { openNiftiVolume(p); }, {p, "scl_inter"});
}

TEST_F(NiftiErrors, BadVoxOffset) {
    NiftiHeaderBuilder h(FileScalar::U8, 2);
    h.setF32(108, 100.0f);
    const std::string p = write("off.nii", h.bytes() + std::string(kSamples, '\0'));
    expectIoError([&] { openNiftiVolume(p); }, {p, "vox_offset 100", "inside the 348-byte header"});
}

TEST_F(NiftiErrors, MissingImageOfPair) {
    NiftiHeaderBuilder h(FileScalar::U8, 2);
    h.setMagic("ni1").setF32(108, 0.0f);
    const std::string hdr = write("lonely.hdr", h.bytes(348));
    expectIoError([&] { openNiftiVolume(hdr); }, {"lonely.img", "cannot open"});
    const std::string nii = write("pair.nii", h.bytes(348));
    expectIoError([&] { openNiftiVolume(nii); }, {nii, "magic 'ni1'", "not named *.hdr"});
}

}  // namespace
}  // namespace vdiso
