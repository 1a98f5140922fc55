// Raw input: sizes checked against the file, byte order, header skipping, type mapping.
#include <gtest/gtest.h>

#include "io/error.h"
#include "io/readers/raw_reader.h"
#include "tests/reader_test_util.h"
#include "tests/test_util.h"

namespace vdiso {
namespace {

using test::ScratchDir;

std::string errorOf(const std::string& path, const RawOptions& o) {
    try {
        auto r = openRawVolume(path, o);
        std::vector<unsigned char> all(r->info().byteSize());
        r->read(all.data(), r->info().dims[2]);
        r->finish();
    } catch (const IoError& e) {
        return e.what();
    }
    return "";
}

TEST(RawReader, ShorterAndLongerFilesSayByHowMuch) {
    ScratchDir dir;
    const std::string path = dir.file("v.raw");
    test::writeFile(path, std::string(100, 'a'));
    RawOptions o;
    o.dims = {5, 5, 5};  // needs 125 bytes
    std::string msg = errorOf(path, o);
    EXPECT_NE(msg.find(path), std::string::npos) << msg;
    EXPECT_NE(msg.find("25 bytes shorter"), std::string::npos) << msg;
    o.dims = {4, 4, 4};  // needs 64
    msg = errorOf(path, o);
    EXPECT_NE(msg.find("36 bytes longer"), std::string::npos) << msg;
    o.dims = {5, 5, 4};
    o.headerBytes = 10;  // 10 + 100 = 110 > 100
    EXPECT_NE(errorOf(path, o).find("10 bytes shorter"), std::string::npos);
}

TEST(RawReader, BigEndianWithHeaderDecodes) {
    ScratchDir dir;
    const std::string path = dir.file("v.raw");
    std::vector<unsigned char> bytes = {'H', 'D', 'R'};
    for (int i = 0; i < 8; ++i) {
        const uint16_t v = uint16_t(1000 + i * 257);
        bytes.push_back(uint8_t(v >> 8));
        bytes.push_back(uint8_t(v & 0xff));
    }
    test::writeFile(path, bytes.data(), bytes.size());
    RawOptions o;
    o.dims = {2, 2, 2};
    o.type = FileScalar::U16;
    o.bigEndian = true;
    o.headerBytes = 3;
    o.spacing = {0.5, 0.25, 2.0};
    auto r = openRawVolume(path, o);
    EXPECT_EQ(r->info().type, ScalarType::U16);
    EXPECT_EQ(r->info().spacing, glm::dvec3(0.5, 0.25, 2.0));
    std::vector<uint16_t> v(8);
    r->read(v.data(), 1);
    r->read(v.data() + 4, 1);
    r->finish();
    for (int i = 0; i < 8; ++i) EXPECT_EQ(v[size_t(i)], 1000 + i * 257);
}

TEST(RawReader, WideTypesMapToTheStoreTypes) {
    ScratchDir dir;
    const std::string path = dir.file("v.raw");
    const double values[8] = {-1.5, 0, 1e6, 2.25, -7, 3, 4, 5};
    test::writeFile(path, values, sizeof values);
    RawOptions o;
    o.dims = {2, 2, 2};
    o.type = FileScalar::F64;
    auto r = openRawVolume(path, o);
    EXPECT_EQ(r->info().type, ScalarType::F32);
    std::vector<float> v(8);
    r->read(v.data(), 2);
    for (int i = 0; i < 8; ++i) EXPECT_EQ(v[size_t(i)], float(values[i]));
}

TEST(RawReader, TooSmallDimensionIsRefused) {
    ScratchDir dir;
    const std::string path = dir.file("v.raw");
    test::writeFile(path, std::string(8, 'a'));
    RawOptions o;
    o.dims = {8, 1, 1};
    EXPECT_NE(errorOf(path, o).find("at least 2 samples"), std::string::npos);
}

TEST(RawReader, SkipMatchesReading) {
    ScratchDir dir;
    const std::string path = dir.file("v.raw");
    std::string bytes = "HDR";
    for (int i = 0; i < 7 * 5 * 6 * 2; ++i) bytes += char(i * 37 % 251);
    test::writeFile(path, bytes);
    RawOptions o;
    o.dims = {7, 5, 6};
    o.type = FileScalar::U16;
    o.bigEndian = true;
    o.headerBytes = 3;
    test::expectSkipMatchesRead([&] { return openRawVolume(path, o); });
    o.type = FileScalar::I8;  // decoded into the store's i16
    o.dims = {7, 10, 6};
    test::expectSkipMatchesRead([&] { return openRawVolume(path, o); });
}

}  // namespace
}  // namespace vdiso
