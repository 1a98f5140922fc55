// NRRD reader: headers as ITK, 3D Slicer and teem write them, attached and detached data, raw
// and gzip, every type and its aliases; and the inputs it must refuse, each with a message that
// names the file and the problem.
#include <gtest/gtest.h>
#include <zlib.h>

#include <stdexcept>
#include <filesystem>
#include <string>
#include <vector>

#include "io/readers/nrrd_reader.h"
#include "io/readers/sample_decode.h"
#include "tests/reader_test_util.h"

namespace vdiso {
namespace {

using test::encodeSamples;
using test::expectDoubleEq;
using test::expectIoError;
using test::gzipBytes;
using test::kDims;
using test::testValues;

void openAndReadAll(const std::string& path) {
    auto reader = openNrrdVolume(path);
    test::readAllValues(*reader);
}

struct TypeSpellings {
    FileScalar type;
    std::vector<std::string> names;  // the first is the one the other tests write
};

// Every spelling teem accepts for the types the store can hold, written out here rather than
// taken from the reader, so a spelling the reader drops fails the test.
const TypeSpellings kTypeSpellings[] = {
    {FileScalar::I8, {"int8", "int8_t", "signed char"}},
    {FileScalar::U8, {"uchar", "unsigned char", "uint8", "uint8_t"}},
    {FileScalar::I16,
     {"short", "short int", "signed short", "signed short int", "int16", "int16_t"}},
    {FileScalar::U16, {"ushort", "unsigned short", "unsigned short int", "uint16", "uint16_t"}},
    {FileScalar::I32, {"int", "signed int", "int32", "int32_t"}},
    {FileScalar::U32, {"uint", "unsigned int", "uint32", "uint32_t"}},
    {FileScalar::F32, {"float"}},
    {FileScalar::F64, {"double"}},
};

const std::string& nrrdTypeName(FileScalar type) {
    for (const TypeSpellings& t : kTypeSpellings)
        if (t.type == type) return t.names.front();
    throw std::logic_error("no NRRD spelling for a file type");
}

class NrrdTest : public test::ReaderFileTest {
protected:
    // A minimal teem-style header; `extra` lines go before the blank line.
    static std::string header(const std::string& type, const std::string& encoding,
                              const std::string& extra = "", const std::string& endian = "little") {
        return "NRRD0004\ntype: " + type + "\ndimension: 3\nsizes: 7 5 4\nendian: " + endian +
               "\nencoding: " + encoding + "\n" + extra;
    }

    static void expectValues(SliceReader& reader, FileScalar type) {
        test::expectValues(reader, testValues(type));
    }
};

using NrrdReader = NrrdTest;
using NrrdErrors = NrrdTest;

TEST_F(NrrdReader, AttachedRawEveryTypeAlias) {
    for (const TypeSpellings& t : kTypeSpellings) {
        for (const std::string& name : t.names) {
            SCOPED_TRACE(name);
            const std::string p =
                write("vol.nrrd", header(name, "raw") + "\n" +
                                      encodeSamples(testValues(t.type), t.type, false));
            auto reader = openNrrdVolume(p);
            EXPECT_EQ(reader->info().dims, kDims);
            EXPECT_EQ(reader->info().type, storeTypeFor(t.type, false));
            EXPECT_EQ(reader->name(), p);
            expectValues(*reader, t.type);
        }
    }
}

TEST_F(NrrdReader, AttachedGzipEveryType) {
    for (FileScalar type : {FileScalar::I8, FileScalar::U8, FileScalar::I16, FileScalar::U16,
                            FileScalar::I32, FileScalar::U32, FileScalar::F32, FileScalar::F64}) {
        SCOPED_TRACE(fileScalarName(type));
        const std::string p =
            write("vol.nrrd", header(nrrdTypeName(type), "gzip") + "\n" +
                                  gzipBytes(encodeSamples(testValues(type), type, false)));
        auto reader = openNrrdVolume(p);
        EXPECT_EQ(reader->info().type, storeTypeFor(type, false));
        expectValues(*reader, type);
    }
}

TEST_F(NrrdReader, GzAliasAndZlibStream) {
    const std::string samples = encodeSamples(testValues(FileScalar::U16), FileScalar::U16, false);
    std::string zlib(compressBound(uLong(samples.size())), '\0');
    uLongf zlibSize = uLongf(zlib.size());
    ASSERT_EQ(compress2(reinterpret_cast<Bytef*>(zlib.data()), &zlibSize,
                        reinterpret_cast<const Bytef*>(samples.data()), uLong(samples.size()), 9),
              Z_OK);
    zlib.resize(zlibSize);
    auto reader = openNrrdVolume(write("vol.nrrd", header("ushort", "gz") + "\n" + zlib));
    expectValues(*reader, FileScalar::U16);
}

TEST_F(NrrdReader, BigEndianEveryMultiByteType) {
    for (FileScalar type : {FileScalar::I16, FileScalar::U16, FileScalar::I32, FileScalar::U32,
                            FileScalar::F32, FileScalar::F64}) {
        SCOPED_TRACE(fileScalarName(type));
        const std::string samples = encodeSamples(testValues(type), type, true);
        auto raw = openNrrdVolume(
            write("raw.nrrd", header(nrrdTypeName(type), "raw", "", "big") + "\n" + samples));
        expectValues(*raw, type);
        auto gz = openNrrdVolume(write(
            "gz.nrrd", header(nrrdTypeName(type), "gzip", "", "big") + "\n" + gzipBytes(samples)));
        expectValues(*gz, type);
    }
}

TEST_F(NrrdReader, DetachedRawWithDataFileForms) {
    const std::string samples = encodeSamples(testValues(FileScalar::I16), FileScalar::I16, false);
    write("vol.raw", samples);
    write("sub/deeper.raw", samples);
    const std::string absolute = write("abs.raw", samples);
    const std::pair<const char*, std::string> cases[] = {
        {"data file", "vol.raw"},
        {"datafile", "vol.raw"},
        {"data file", "./sub/deeper.raw"},
        {"data file", absolute},
    };
    for (const auto& [field, file] : cases) {
        SCOPED_TRACE(file);
        // Detached headers need not end with a blank line.
        const std::string p =
            write("vol.nhdr", header("short", "raw", std::string(field) + ": " + file + "\n"));
        auto reader = openNrrdVolume(p);
        EXPECT_EQ(reader->name(), p);
        expectValues(*reader, FileScalar::I16);
    }
}

TEST_F(NrrdReader, DetachedHeaderInAnotherDirectory) {
    write("data/vol.raw.gz",
          gzipBytes(encodeSamples(testValues(FileScalar::F32), FileScalar::F32, false)));
    auto reader = openNrrdVolume(
        write("headers/vol.nhdr", header("float", "gzip", "data file: ../data/vol.raw.gz\n\n")));
    expectValues(*reader, FileScalar::F32);
}

TEST_F(NrrdReader, ItkStyleHeader) {
    const std::string text =
        "NRRD0004\n"
        "# Complete NRRD file format specification at:\n"
        "# http://teem.sourceforge.net/nrrd/format.html\n"
        "type: short\n"
        "dimension: 3\n"
        "space: left-posterior-superior\n"
        "sizes: 7 5 4\n"
        "space directions: (0.5,0,0) (0,0.75,0) (0,0,2.5)\n"
        "kinds: domain domain domain\n"
        "endian: little\n"
        "encoding: gzip\n"
        "space origin: (-10.5,20,3.25)\n"
        "ITK_InputFilterName:=NrrdImageIO\n"
        "\n";
    auto reader = openNrrdVolume(write(
        "itk.nrrd",
        text + gzipBytes(encodeSamples(testValues(FileScalar::I16), FileScalar::I16, false))));
    const VolumeInfo& info = reader->info();
    EXPECT_EQ(info.dims, kDims);
    EXPECT_EQ(info.type, ScalarType::I16);
    expectDoubleEq(info.spacing, {0.5, 0.75, 2.5});
    expectDoubleEq(info.origin, {-10.5, 20.0, 3.25});
    expectValues(*reader, FileScalar::I16);
}

TEST_F(NrrdReader, SlicerStyleDetachedHeaderWithCrlfAndObliqueDirections) {
    // Slicer writes oblique directions as they come from DICOM; spacing is their length.
    const std::string text =
        "NRRD0004\r\n"
        "# Complete NRRD file format specification at:\r\n"
        "# http://teem.sourceforge.net/nrrd/format.html\r\n"
        "type: unsigned short\r\n"
        "dimension: 3\r\n"
        "space: left-posterior-superior\r\n"
        "sizes: 7 5 4\r\n"
        "space directions: (0,0.6,0.8) (-2, 0, 0) ( 0 , 0 , -1.5 )\r\n"
        "kinds: domain domain domain\r\n"
        "endian: little\r\n"
        "encoding: raw\r\n"
        "space units: \"mm\" \"mm\" \"mm\"\r\n"
        "space origin: (119.5,119.5,-60)\r\n"
        "measurement frame: (1,0,0) (0,1,0) (0,0,1)\r\n"
        "data file: slicer.raw\r\n"
        "DICOM_0008_0060:={\"modality\":\"CT\"}\r\n"
        "\r\n";
    write("slicer.raw", encodeSamples(testValues(FileScalar::U16), FileScalar::U16, false));
    auto reader = openNrrdVolume(write("slicer.nhdr", text));
    const VolumeInfo& info = reader->info();
    EXPECT_EQ(info.type, ScalarType::U16);
    expectDoubleEq(info.spacing, {1.0, 2.0, 1.5});
    expectDoubleEq(info.origin, {119.5, 119.5, -60.0});
    // LPS already; the directions normalised and kept as they are (a shear: i is not at right
    // angles to k).
    EXPECT_TRUE(info.hasOrientation);
    test::expectDirection(info.direction, glm::dmat3(0, 0.6, 0.8, -1, 0, 0, 0, 0, -1), 1e-12);
    expectValues(*reader, FileScalar::U16);
}

// Space directions in RAS, LAS and LPS: a quarter turn about z with the third axis flipped,
// with steps of 2, 0.5, 3; each converted to LPS with its origin.
TEST_F(NrrdReader, SpaceDirectionsInEveryAnatomicalSpaceGiveLps) {
    const std::string samples = encodeSamples(testValues(FileScalar::U8), FileScalar::U8, false);
    struct Case {
        const char* space;
        glm::dvec3 flip;  // what the space's x, y, z are in LPS
    };
    for (const Case& c : {Case{"right-anterior-superior", {-1, -1, 1}}, Case{"RAS", {-1, -1, 1}},
                          Case{"left-anterior-superior", {1, -1, 1}},
                          Case{"left-posterior-superior", {1, 1, 1}}, Case{"LPS", {1, 1, 1}}}) {
        SCOPED_TRACE(c.space);
        const std::string header = std::string("NRRD0005\ntype: uchar\ndimension: 3\nspace: ") + c.space +
                                   "\nsizes: 7 5 4\nspace directions: (0,2,0) (-0.5,0,0) (0,0,-3)\n"
                                   "space origin: (1.5,-2.5,7)\nencoding: raw\n\n";
        auto reader = openNrrdVolume(write("oriented.nrrd", header + samples));
        const VolumeInfo& info = reader->info();
        EXPECT_TRUE(info.hasOrientation);
        expectDoubleEq(info.spacing, {2.0, 0.5, 3.0});
        const glm::dmat3 flip(glm::dvec3(c.flip.x, 0, 0), glm::dvec3(0, c.flip.y, 0), glm::dvec3(0, 0, c.flip.z));
        test::expectDirection(info.direction, flip * glm::dmat3(0, 1, 0, -1, 0, 0, 0, 0, -1), 1e-12);
        expectDoubleEq(info.origin, flip * glm::dvec3(1.5, -2.5, 7.0));
        expectValues(*reader, FileScalar::U8);
    }
}

// Spaces without patient directions, and no space at all, give no orientation; the
// directions still give the spacing and the origin is as written.
TEST_F(NrrdReader, NonAnatomicalSpaceHasNoOrientation) {
    const std::string samples = encodeSamples(testValues(FileScalar::U8), FileScalar::U8, false);
    for (const char* space : {"space: scanner-xyz\n", "space: 3D-right-handed\n", "space dimension: 3\n"}) {
        SCOPED_TRACE(space);
        const std::string header = std::string("NRRD0005\ntype: uchar\ndimension: 3\n") + space +
                                   "sizes: 7 5 4\nspace directions: (0,2,0) (-0.5,0,0) (0,0,-3)\n"
                                   "space origin: (1.5,-2.5,7)\nencoding: raw\n\n";
        auto reader = openNrrdVolume(write("plain.nrrd", header + samples));
        EXPECT_FALSE(reader->info().hasOrientation);
        EXPECT_EQ(reader->info().direction, glm::dmat3(1.0));
        expectDoubleEq(reader->info().spacing, {2.0, 0.5, 3.0});
        expectDoubleEq(reader->info().origin, {1.5, -2.5, 7.0});
    }
}

TEST_F(NrrdErrors, SingularNonFiniteOrUnknownSpaceIsRefused) {
    const std::string samples = encodeSamples(testValues(FileScalar::U8), FileScalar::U8, false);
    auto headerWith = [](const std::string& space, const std::string& directions) {
        return "NRRD0005\ntype: uchar\ndimension: 3\nspace: " + space + "\nsizes: 7 5 4\n" +
               "space directions: " + directions + "\nencoding: raw\n\n";
    };
    const std::string singular = write("singular.nrrd", headerWith("RAS", "(1,0,0) (2,0,0) (0,0,1)") + samples);
    expectIoError([&] { openNrrdVolume(singular); }, {singular, "space directions", "singular"});
    const std::string nan = write("nan.nrrd", headerWith("LPS", "(nan,0,0) (0,1,0) (0,0,1)") + samples);
    expectIoError([&] { openNrrdVolume(nan); }, {nan, "space directions", "not finite"});
    const std::string unknown = write("unknown.nrrd", headerWith("north-east-up", "(1,0,0) (0,1,0) (0,0,1)") + samples);
    expectIoError([&] { openNrrdVolume(unknown); }, {unknown, "unknown NRRD space 'north-east-up'"});
}

TEST_F(NrrdReader, TeemSpacingsAndUnknownFields) {
    const std::string extra =
        "content: resample(head)\n"
        "spacings: -0.5 nan 3\n"
        "centers: cell cell cell\n"
        "some future field: 1 2 3\n"
        "key with spaces:=value: with colon\n";
    auto reader = openNrrdVolume(
        write("teem.nrrd", "NRRD0001\n" + header("uchar", "raw", extra).substr(9) + "\n" +
                               encodeSamples(testValues(FileScalar::U8), FileScalar::U8, false)));
    const VolumeInfo& info = reader->info();
    expectDoubleEq(info.spacing, {0.5, 1.0, 3.0});
    EXPECT_EQ(info.origin, glm::dvec3(0.0));
    expectValues(*reader, FileScalar::U8);
}

TEST_F(NrrdReader, FourDimensionsWithSingletonAxis) {
    const std::string samples = encodeSamples(testValues(FileScalar::F32), FileScalar::F32, false);
    const std::string leading =
        "NRRD0005\ntype: float\ndimension: 4\nspace: RAS\nsizes: 1 7 5 4\n"
        "space directions: none (2,0,0) (0,3,0) (0,0,4)\nkinds: vector domain domain domain\n"
        "endian: little\nencoding: raw\n\n";
    auto reader = openNrrdVolume(write("leading.nrrd", leading + samples));
    EXPECT_EQ(reader->info().dims, kDims);
    EXPECT_EQ(reader->info().spacing, glm::dvec3(2.0, 3.0, 4.0));
    expectValues(*reader, FileScalar::F32);

    const std::string trailing =
        "NRRD0004\ntype: float\ndimension: 4\nsizes: 7 5 4 1\nspacings: 2 3 4 nan\n"
        "endian: little\nencoding: raw\n\n";
    reader = openNrrdVolume(write("trailing.nrrd", trailing + samples));
    EXPECT_EQ(reader->info().dims, kDims);
    EXPECT_EQ(reader->info().spacing, glm::dvec3(2.0, 3.0, 4.0));
    expectValues(*reader, FileScalar::F32);
}

TEST_F(NrrdReader, LineSkipAndByteSkip) {
    const std::string samples = encodeSamples(testValues(FileScalar::I16), FileScalar::I16, false);
    write("skip.raw", "first line\nsecond line\n" + std::string(10, 'x') + samples);
    auto reader = openNrrdVolume(write("skip.nhdr", header("short", "raw",
                                                           "line skip: 2\nbyte skip: 10\n"
                                                           "data file: skip.raw\n")));
    expectValues(*reader, FileScalar::I16);

    // With gzip, line skip counts lines of the file and byte skip decompressed bytes.
    write("skip.gz", "a line\n" + gzipBytes(std::string(6, 'y') + samples));
    reader = openNrrdVolume(
        write("skipgz.nhdr",
              header("short", "gzip", "line skip: 1\nbyte skip: 6\ndata file: skip.gz\n")));
    expectValues(*reader, FileScalar::I16);
}

TEST_F(NrrdReader, ByteSkipMinusOneReadsFromTheEnd) {
    const std::string samples = encodeSamples(testValues(FileScalar::U16), FileScalar::U16, false);
    write("tail.raw", std::string(123, '\0') + samples);
    auto reader = openNrrdVolume(
        write("tail.nhdr", header("ushort", "raw", "byte skip: -1\ndata file: tail.raw\n")));
    expectValues(*reader, FileScalar::U16);
}

TEST_F(NrrdErrors, DataFileThatIsADirectoryIsNamed) {
    // Was "basic_filebuf::underflow error reading the file: Is a directory", the C++ library's
    // words, when a line skip read into it.
    std::filesystem::create_directories(path("dir.raw"));
    for (const char* skip : {"line skip: 2\n", "", "byte skip: 4\n"}) {
        SCOPED_TRACE(skip);
        const std::string p =
            write("dir.nhdr", header("short", "raw", std::string(skip) + "data file: dir.raw\n"));
        expectIoError([&] { openNrrdVolume(p); }, {p, path("dir.raw"), "is a directory"});
    }
}

TEST_F(NrrdErrors, RawDataShorterThanSizes) {
    std::string samples = encodeSamples(testValues(FileScalar::I16), FileScalar::I16, false);
    samples.resize(samples.size() - 3);
    const std::string p = write("short.nrrd", header("short", "raw") + "\n" + samples);
    expectIoError([&] { openNrrdVolume(p); }, {p, "3 bytes shorter"});
}

TEST_F(NrrdErrors, RawDataLongerThanSizes) {
    const std::string samples =
        encodeSamples(testValues(FileScalar::I16), FileScalar::I16, false) + "12345";
    const std::string p = write("long.nrrd", header("short", "raw") + "\n" + samples);
    expectIoError([&] { openNrrdVolume(p); }, {p, "5 bytes longer"});
}

TEST_F(NrrdErrors, DetachedDataShorterNamesTheDataFile) {
    const std::string data = write("d.raw", std::string(100, '\0'));
    const std::string p = write("d.nhdr", header("uchar", "raw", "data file: d.raw\n"));
    expectIoError([&] { openNrrdVolume(p); }, {data, "40 bytes shorter", "d.nhdr"});
}

TEST_F(NrrdErrors, ByteSkipMinusOneWithTooLittleData) {
    write("t.raw", std::string(100, '\0'));
    const std::string p =
        write("t.nhdr", header("uchar", "raw", "byte skip: -1\ndata file: t.raw\n"));
    expectIoError([&] { openNrrdVolume(p); }, {"t.raw", "40 bytes shorter"});
}

TEST_F(NrrdErrors, GzipDataShorterThanSizes) {
    std::string samples = encodeSamples(testValues(FileScalar::U8), FileScalar::U8, false);
    samples.resize(samples.size() - 1);
    const std::string p = write("short.nrrd", header("uchar", "gzip") + "\n" + gzipBytes(samples));
    expectIoError([&] { openAndReadAll(p); }, {p, "ends after"});
}

TEST_F(NrrdErrors, GzipDataLongerThanSizes) {
    const std::string samples =
        encodeSamples(testValues(FileScalar::U8), FileScalar::U8, false) + "x";
    const std::string p = write("long.nrrd", header("uchar", "gzip") + "\n" + gzipBytes(samples));
    expectIoError([&] { openAndReadAll(p); }, {p, "holds more data than its header describes"});
}

TEST_F(NrrdErrors, CorruptGzip) {
    std::string gz =
        gzipBytes(encodeSamples(test::incompressibleU16Values(), FileScalar::U16, false));
    for (size_t i = gz.size() / 2 - 4; i < gz.size() / 2 + 4; ++i) gz[i] = char(~gz[i]);
    const std::string p = write("corrupt.nrrd", header("ushort", "gzip") + "\n" + gz);
    expectIoError([&] { openAndReadAll(p); }, {p, "corrupt gzip data"});
}

TEST_F(NrrdErrors, TruncatedGzip) {
    std::string gz = gzipBytes(encodeSamples(testValues(FileScalar::F64), FileScalar::F64, false));
    gz.resize(gz.size() / 2);
    const std::string p = write("trunc.nrrd", header("double", "gzip") + "\n" + gz);
    expectIoError([&] { openAndReadAll(p); }, {p, "truncated"});
}

TEST_F(NrrdErrors, UnknownType) {
    const std::string p = write("t.nrrd", header("quad", "raw") + "\n");
    expectIoError([&] { openNrrdVolume(p); }, {p, "unknown NRRD type 'quad'"});
}

TEST_F(NrrdErrors, SixtyFourBitAndBlockTypes) {
    for (const char* type : {"long long", "int64", "unsigned long long", "uint64_t"}) {
        const std::string p = write("t.nrrd", header(type, "raw") + "\n");
        expectIoError([&] { openNrrdVolume(p); },
                      {p, "NRRD type '" + std::string(type) + "' is not supported"});
    }
    const std::string p = write("b.nrrd", header("block", "raw", "block size: 4\n") + "\n");
    expectIoError([&] { openNrrdVolume(p); }, {p, "NRRD type 'block' is not supported"});
}

TEST_F(NrrdErrors, UnsupportedEncodings) {
    for (const char* encoding : {"ascii", "text", "txt", "hex", "bzip2", "bz2", "zrl"}) {
        const std::string p = write("e.nrrd", header("uchar", encoding) + "\n");
        expectIoError([&] { openNrrdVolume(p); },
                      {p, "unsupported NRRD encoding '" + std::string(encoding) + "'"});
    }
}

TEST_F(NrrdErrors, NotThreeDimensional) {
    const std::string two =
        write("two.nrrd", "NRRD0004\ntype: uchar\ndimension: 2\nsizes: 7 5\nencoding: raw\n\n" +
                              std::string(35, '\0'));
    expectIoError([&] { openNrrdVolume(two); },
                  {two, "dimension 2", "only scalar 3-D volumes are supported"});
    const std::string four = write(
        "four.nrrd", "NRRD0004\ntype: uchar\ndimension: 4\nsizes: 3 7 5 4\nencoding: raw\n\n" +
                         std::string(420, '\0'));
    expectIoError([&] { openNrrdVolume(four); },
                  {four, "dimension 4", "only scalar 3-D volumes are supported"});
}

TEST_F(NrrdErrors, BadMagic) {
    const std::string p = write("bad.nrrd", "NRRX0004\ntype: uchar\n\n");
    expectIoError([&] { openNrrdVolume(p); }, {p, "not a NRRD file"});
    const std::string binary = write("binary.nrrd", std::string(100000, '\x01'));
    expectIoError([&] { openNrrdVolume(binary); }, {binary, "not a NRRD file"});
    const std::string empty = write("empty.nrrd", "");
    expectIoError([&] { openNrrdVolume(empty); }, {empty, "not a NRRD file"});
}

TEST_F(NrrdErrors, MissingFieldsAndFiles) {
    const std::string noEndian =
        write("e.nrrd", "NRRD0004\ntype: short\ndimension: 3\nsizes: 7 5 4\nencoding: raw\n\n");
    expectIoError([&] { openNrrdVolume(noEndian); }, {noEndian, "'endian'"});
    const std::string noSizes =
        write("s.nrrd", "NRRD0004\ntype: uchar\ndimension: 3\nencoding: raw\n\n");
    expectIoError([&] { openNrrdVolume(noSizes); }, {noSizes, "no 'sizes' field"});
    const std::string missing = write("m.nhdr", header("uchar", "raw", "data file: nowhere.raw\n"));
    expectIoError([&] { openNrrdVolume(missing); }, {"nowhere.raw", "cannot open"});
    expectIoError([&] { openNrrdVolume(path("absent.nrrd")); }, {"absent.nrrd", "cannot open"});
    const std::string noBlank = write("nb.nrrd", header("uchar", "raw"));
    expectIoError([&] { openNrrdVolume(noBlank); }, {noBlank, "has no data"});
}

TEST_F(NrrdErrors, MultiFileDataRefused) {
    const std::string list =
        write("list.nhdr", header("uchar", "raw", "data file: LIST\nslice0.raw\nslice1.raw\n"));
    expectIoError([&] { openNrrdVolume(list); }, {list, "'data file: LIST'", "not supported"});
    const std::string format =
        write("fmt.nhdr", header("uchar", "raw", "data file: slice%03d.raw 1 4 1 2\n"));
    expectIoError([&] { openNrrdVolume(format); }, {format, "multi-file", "not supported"});
}

TEST_F(NrrdErrors, AxisTooSmall) {
    const std::string p =
        write("flat.nrrd", "NRRD0004\ntype: uchar\ndimension: 3\nsizes: 7 5 1\nencoding: raw\n\n" +
                               std::string(35, '\0'));
    expectIoError([&] { openNrrdVolume(p); }, {p, "at least 2 samples"});
}

TEST_F(NrrdErrors, MalformedHeaderValues) {
    const std::string sizes =
        write("s.nrrd", "NRRD0004\ntype: uchar\ndimension: 3\nsizes: 7 x 4\nencoding: raw\n\n");
    expectIoError([&] { openNrrdVolume(sizes); }, {sizes, "'sizes'", "'x'"});
    const std::string dirs =
        write("d.nrrd", header("uchar", "raw", "space directions: (1,0,0) (0,1,0)\n") + "\n" +
                            std::string(140, '\0'));
    expectIoError([&] { openNrrdVolume(dirs); }, {dirs, "'space directions' has 2 entries"});
}

TEST_F(NrrdReader, SkipSeeksInRawAndDecompressesGzip) {
    for (const char* encoding : {"raw", "gzip"}) {
        SCOPED_TRACE(encoding);
        const std::string samples = encodeSamples(testValues(FileScalar::I32), FileScalar::I32, false);
        const std::string p = write("vol.nrrd", header("int32", encoding) + "\n" +
                                                    (std::string(encoding) == "raw" ? samples : gzipBytes(samples)));
        test::expectSkipMatchesRead([&] { return openNrrdVolume(p); });
    }
}

}  // namespace
}  // namespace vdiso
