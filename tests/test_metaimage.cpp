// MetaImage reader: .mha with LOCAL data and .mhd with a data file, raw and zlib-compressed,
// every element type, either byte order, HeaderSize; and the headers it must refuse by name.
#include <gtest/gtest.h>
#include <zlib.h>

#include <string>
#include <vector>

#include "io/store/brick_store.h"
#include "io/error.h"
#include "io/readers/metaimage_reader.h"
#include "io/readers/sample_decode.h"
#include "io/readers/volume_open.h"
#include "tests/reader_test_util.h"

namespace vdiso {
namespace {

using test::encodeSamples;
using test::expectIoError;
using test::kDims;
using test::testValues;

const std::pair<FileScalar, const char*> kTypes[] = {
    {FileScalar::I8, "MET_CHAR"},   {FileScalar::U8, "MET_UCHAR"}, {FileScalar::I16, "MET_SHORT"},
    {FileScalar::U16, "MET_USHORT"}, {FileScalar::I32, "MET_INT"},  {FileScalar::U32, "MET_UINT"},
    {FileScalar::F32, "MET_FLOAT"}, {FileScalar::F64, "MET_DOUBLE"}};

// ITK writes zlib streams (compress2), not gzip.
std::string zlibBytes(const std::string& data) {
    std::string out(compressBound(uLong(data.size())), '\0');
    uLongf size = uLongf(out.size());
    compress2(reinterpret_cast<Bytef*>(out.data()), &size,
              reinterpret_cast<const Bytef*>(data.data()), uLong(data.size()), 6);
    out.resize(size);
    return out;
}

// A header as ITK's MetaImageIO writes it, up to (not including) ElementDataFile.
std::string header(const char* type, const std::string& extra = "") {
    return "ObjectType = Image\nNDims = 3\nBinaryData = True\nBinaryDataByteOrderMSB = False\n"
           "TransformMatrix = 1 0 0 0 1 0 0 0 1\nOffset = -10.5 20 3.25\n"
           "CenterOfRotation = 0 0 0\nAnatomicalOrientation = RAI\n"
           "ElementSpacing = 0.5 0.75 2.5\nDimSize = 7 5 4\n" + extra + "ElementType = " + type + "\n";
}

class MetaImageTest : public test::ReaderFileTest {};
using MetaImageReader = MetaImageTest;
using MetaImageErrors = MetaImageTest;

TEST_F(MetaImageReader, LocalRawAndCompressedEveryType) {
    for (const auto& [type, name] : kTypes) {
        SCOPED_TRACE(name);
        const std::string samples = encodeSamples(testValues(type), type, false);
        auto raw = openMetaImageVolume(
            write("v.mha", header(name) + "ElementDataFile = LOCAL\n" + samples));
        EXPECT_EQ(raw->info().dims, kDims);
        EXPECT_EQ(raw->info().type, storeTypeFor(type, false));
        test::expectDoubleEq(raw->info().spacing, glm::dvec3(0.5, 0.75, 2.5));
        test::expectDoubleEq(raw->info().origin, glm::dvec3(-10.5, 20.0, 3.25));
        test::expectValues(*raw, testValues(type));
        const std::string z = zlibBytes(samples);
        auto compressed = openMetaImageVolume(write(
            "c.mha", header(name, "CompressedData = True\nCompressedDataSize = " +
                                      std::to_string(z.size()) + "\n") +
                         "ElementDataFile = LOCAL\n" + z));
        test::expectValues(*compressed, testValues(type));
    }
}

// TransformMatrix as ITK writes it: NDims groups, group a the LPS direction of axis a (here a
// quarter turn about z and k flipped; a group's length does not matter). Offset is LPS too.
TEST_F(MetaImageReader, TransformMatrixGivesLpsDirection) {
    const std::string samples = encodeSamples(testValues(FileScalar::U8), FileScalar::U8, false);
    auto reader = openMetaImageVolume(write(
        "o.mha", header("MET_UCHAR", "TransformMatrix = 0 -2 0 1 0 0 0 0 -1\n") + "ElementDataFile = LOCAL\n" + samples));
    const VolumeInfo& info = reader->info();
    EXPECT_TRUE(info.hasOrientation);
    test::expectDirection(info.direction, glm::dmat3(0, -1, 0, 1, 0, 0, 0, 0, -1), 1e-12);
    test::expectDoubleEq(info.origin, glm::dvec3(-10.5, 20.0, 3.25));
    test::expectDoubleEq(info.spacing, glm::dvec3(0.5, 0.75, 2.5));
    test::expectValues(*reader, testValues(FileScalar::U8));
    // The identity ITK writes for every image is an orientation: i to the left, j posterior.
    auto identity = openMetaImageVolume(write("i.mha", header("MET_UCHAR") + "ElementDataFile = LOCAL\n" + samples));
    EXPECT_TRUE(identity->info().hasOrientation);
    EXPECT_EQ(identity->info().direction, glm::dmat3(1.0));
    // Without a TransformMatrix, none.
    auto none = openMetaImageVolume(write(
        "n.mha", "NDims = 3\nDimSize = 7 5 4\nElementType = MET_UCHAR\nElementDataFile = LOCAL\n" + samples));
    EXPECT_FALSE(none->info().hasOrientation);
}

TEST_F(MetaImageErrors, SingularOrNonFiniteTransformMatrixIsRefused) {
    const std::string samples = encodeSamples(testValues(FileScalar::U8), FileScalar::U8, false);
    const std::pair<const char*, const char*> cases[] = {
        {"TransformMatrix = 1 0 0 1 0 0 0 0 1\n", "singular"},
        {"TransformMatrix = 1 0 0 0 nan 0 0 0 1\n", "not finite"},
        {"TransformMatrix = 1 0 0 0 0 0 0 0 1\n", "zero vector"},
        {"TransformMatrix = 1 0 0 0 1 0\n", "NDims 3 needs 9"},
    };
    for (const auto& [line, what] : cases) {
        SCOPED_TRACE(line);
        const std::string p = write("bad.mha", header("MET_UCHAR", line) + "ElementDataFile = LOCAL\n" + samples);
        expectIoError([&] { openMetaImageVolume(p); }, {p, "TransformMatrix", what});
    }
}

TEST_F(MetaImageReader, DetachedDataBigEndianAndHeaderSize) {
    const FileScalar type = FileScalar::I16;
    write("data/v.raw", std::string(100, 'x') + encodeSamples(testValues(type), type, true));
    auto reader = openMetaImageVolume(
        write("v.mhd", "NDims = 3\nDimSize = 7 5 4\nElementType = MET_SHORT\n"
                       "ElementByteOrderMSB = True\nHeaderSize = 100\nElementSize = 1 2 3\n"
                       "ElementDataFile = data/v.raw\n"));
    test::expectDoubleEq(reader->info().spacing, glm::dvec3(1, 2, 3));
    EXPECT_EQ(reader->files().size(), 2u);
    test::expectValues(*reader, testValues(type));
    // HeaderSize -1: the data ends the file, whatever precedes it.
    auto atEnd = openMetaImageVolume(
        write("e.mhd", "NDims = 3\nDimSize = 7 5 4\nElementType = MET_SHORT\n"
                       "BinaryDataByteOrderMSB = True\nHeaderSize = -1\nElementDataFile = data/v.raw\n"));
    test::expectValues(*atEnd, testValues(type));
    // Through volume_open and the command line.
    EXPECT_EQ(detectInputFormat(path("v.mhd"), {}), InputFormat::MetaImage);
    const auto r = test::runVdiso("convert " + path("v.mhd") + " " + path("v.vdiso") + " --quiet");
    ASSERT_EQ(r.exitCode, 0) << r.output;
    const BrickStoreReader store(path("v.vdiso"));
    const std::string samples = encodeSamples(testValues(type), type, false);
    EXPECT_EQ(test::compareStoreWithSamples(
                  store, std::vector<unsigned char>(samples.begin(), samples.end())),
              "");
}

TEST_F(MetaImageErrors, BadHeadersAreNamed) {
    const std::string samples = encodeSamples(testValues(FileScalar::U8), FileScalar::U8, false);
    const std::pair<std::string, std::string> cases[] = {
        {header("MET_UCHAR") + "ElementDataFile = LOCAL\n" + samples.substr(1), "1 bytes shorter"},
        {header("MET_UCHAR") + "ElementDataFile = LOCAL\n" + samples + "!", "1 bytes longer"},
        {header("MET_LONG_LONG") + "ElementDataFile = LOCAL\n", "64-bit"},
        {header("MET_FLOAT_ARRAY") + "ElementDataFile = LOCAL\n", "only scalar"},
        {header("MET_QUAD") + "ElementDataFile = LOCAL\n", "unknown ElementType"},
        {header("MET_UCHAR", "ElementNumberOfChannels = 3\n") + "ElementDataFile = LOCAL\n", "single-channel"},
        {header("MET_UCHAR", "BinaryData = False\n") + "ElementDataFile = LOCAL\n", "ASCII"},
        {header("MET_UCHAR"), "without an ElementDataFile"},
        {header("MET_UCHAR") + "ElementDataFile = LIST\n", "several files"},
        {header("MET_UCHAR") + "ElementDataFile = s%03d.raw 1 4 1\n", "several files"},
        {"ObjectType = Image\nNDims = 2\nDimSize = 7 5\nElementType = MET_UCHAR\nElementDataFile = LOCAL\n", "only 3-D"},
        {"NDims = 3\nDimSize = 7 5\nElementType = MET_UCHAR\nElementDataFile = LOCAL\n", "DimSize has 2 entries"},
        {"NDims = 3\nDimSize = 4294967296 4294967296 2\nElementType = MET_UCHAR\nElementDataFile = LOCAL\n", "at most 2^31"},
        {"ObjectType = Mesh\n", "not Image"},
        {"NDims = three\n", "not a number"},
        {"\x89PNG\r\n\x1a\n", "not 'Key = Value'"},
        {header("MET_UCHAR", "CompressedData = True\n") + "ElementDataFile = LOCAL\nnot zlib at all", "corrupt"},
    };
    for (const auto& [text, part] : cases) {
        SCOPED_TRACE(part);
        const std::string p = write("bad.mha", text);
        expectIoError(
            [&] {
                auto reader = openMetaImageVolume(p);
                test::readAllValues(*reader);
            },
            {p, part});
    }
    expectIoError([&] { openMetaImageVolume(write("m.mhd", header("MET_UCHAR") + "ElementDataFile = none.raw\n")); },
                  {"none.raw"});
}

// Every truncation of a compressed .mha is refused by name.
TEST_F(MetaImageErrors, EveryTruncation) {
    const std::string samples = test::encodeSamples(test::incompressibleU16Values(), FileScalar::U16, false);
    const std::string bytes =
        header("MET_USHORT", "CompressedData = True\n") + "ElementDataFile = LOCAL\n" + zlibBytes(samples);
    for (size_t n = 0; n < bytes.size(); n += 3) {
        SCOPED_TRACE(n);
        const std::string p = write("t.mha", bytes.substr(0, n));
        try {
            auto reader = openMetaImageVolume(p);
            test::readAllValues(*reader);
            ADD_FAILURE() << "a truncated file was read";
        } catch (const IoError& e) {
            EXPECT_NE(std::string(e.what()).find(p), std::string::npos) << e.what();
        }
    }
}

}  // namespace
}  // namespace vdiso
