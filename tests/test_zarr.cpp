// Zarr reader: stores written here by hand after the Zarr v2/v3 and OME-Zarr v0.4/v0.5
// specifications (blosc, zstd, gzip, no compressor; "." and "/" keys; partial edge chunks; an
// image with two levels) and read back sample for sample; missing chunks as the fill value; and
// what it must refuse by name (a corrupt chunk, a level that is not there, unsupported codecs).
#include <gtest/gtest.h>


#include <cstring>
#include <filesystem>
#include <functional>
#include <string>
#include <vector>

#include "io/store/brick_store.h"
#include "io/error.h"
#include "io/readers/sample_decode.h"
#include "io/readers/volume_open.h"
#include "io/readers/zarr_array.h"
#include "io/readers/zarr_reader.h"
#include "tests/loopback_servers.h"
#include "tests/reader_test_util.h"
#include "tests/zarr_test_util.h"

namespace vdiso {
namespace {

using test::expectIoError;
using test::ArraySpec;
using test::Codec;
using test::writeArray;

// Values of a volume: sample (x, y, z) of an nx x ny x nz u16 volume.
double value(int64_t x, int64_t y, int64_t z) { return test::zarrTestValue(x, y, z); }

std::vector<double> volumeValues(const Dims3& d, int step = 1) {
    std::vector<double> v;
    for (int64_t z = 0; z < d[2]; ++z)
        for (int64_t y = 0; y < d[1]; ++y)
            for (int64_t x = 0; x < d[0]; ++x) v.push_back(value(x * step, y * step, z * step));
    return v;
}

class ZarrTest : public test::ReaderFileTest {};
using ZarrReader = ZarrTest;
using ZarrErrors = ZarrTest;

TEST_F(ZarrReader, PlainArraysEveryCodecBothFormats) {
    for (int format : {2, 3})
        for (Codec codec : {Codec::None, Codec::Blosc, Codec::Zstd, Codec::Gzip})
            for (char separator : {'.', '/'}) {
                SCOPED_TRACE("v" + std::to_string(format) + " codec " + std::to_string(int(codec)) +
                             " separator " + separator);
                ArraySpec a;
                a.format = format;
                a.codec = codec;
                a.separator = separator;
                a.bigEndian = codec == Codec::Zstd;
                const std::string dir = path("a" + std::to_string(format) + std::to_string(int(codec)) + (separator == '.' ? "d" : "s"));
                writeArray(dir, a);
                EXPECT_EQ(detectInputFormat(dir, {}), InputFormat::Zarr);
                auto reader = openVolume(dir, {});
                EXPECT_EQ(reader->info().dims, a.dims);
                EXPECT_EQ(reader->info().type, ScalarType::U16);
                EXPECT_EQ(reader->info().spacing, glm::dvec3(1.0));
                test::expectValues(*reader, volumeValues(a.dims));
            }
}

// An OME-Zarr image with two levels: level 1 is every other sample, at twice the spacing.
void writeOmeImage(const std::filesystem::path& root, int format, const Dims3& dims = {13, 10, 9},
                   std::function<bool(int64_t, int64_t, int64_t)> skip = {}) {
    ArraySpec full;
    full.format = format;
    full.extraAxes = 2;  // t, c
    full.dims = dims;
    full.skip = std::move(skip);
    ArraySpec half = full;
    half.dims = {(dims[0] + 1) / 2, (dims[1] + 1) / 2, (dims[2] + 1) / 2};
    half.step = 2;
    writeArray(root / "0", full);
    writeArray(root / "1", half);
    const std::string multiscales =
        R"([{"version": ")" + std::string(format == 2 ? "0.4" : "0.5") + R"(", "name": "ct", "axes": [)"
        R"({"name": "t", "type": "time"}, {"name": "c", "type": "channel"}, )"
        R"({"name": "z", "type": "space", "unit": "micrometer"}, {"name": "y", "type": "space"}, )"
        R"({"name": "x", "type": "space"}], "datasets": [)"
        R"({"path": "0", "coordinateTransformations": [{"type": "scale", "scale": [1, 1, 2.0, 0.75, 0.5]}, )"
        R"({"type": "translation", "translation": [0, 0, 30, 20, -10]}]}, )"
        R"({"path": "1", "coordinateTransformations": [{"type": "scale", "scale": [1, 1, 4.0, 1.5, 1.0]}, )"
        R"({"type": "translation", "translation": [0, 0, 31, 20.375, -9.75]}]}]}])";
    if (format == 2) {
        test::writeFile((root / ".zgroup").string(), R"({"zarr_format": 2})");
        test::writeFile((root / ".zattrs").string(), R"({"multiscales": )" + multiscales + "}");
    } else {
        test::writeFile((root / "zarr.json").string(),
                        R"({"zarr_format": 3, "node_type": "group", "attributes": {"ome": )"
                        R"({"version": "0.5", "multiscales": )" + multiscales + "}}}");
    }
}

TEST_F(ZarrReader, OmeZarrTwoLevelsBothVersions) {
    for (int format : {2, 3}) {
        SCOPED_TRACE(format == 2 ? "OME-Zarr 0.4" : "OME-Zarr 0.5");
        const std::string root = path(format == 2 ? "v04.ome.zarr" : "v05.ome.zarr");
        writeOmeImage(root, format);
        EXPECT_EQ(detectInputFormat(root, {}), InputFormat::Zarr);
        auto level0 = openZarrVolume(root, 0);
        EXPECT_EQ(level0->info().dims, (Dims3{13, 10, 9}));
        test::expectDoubleEq(level0->info().spacing, glm::dvec3(0.5, 0.75, 2.0));
        test::expectDoubleEq(level0->info().origin, glm::dvec3(-10.0, 20.0, 30.0));
        test::expectValues(*level0, volumeValues({13, 10, 9}));
        InputOptions options;
        options.scaleLevel = 1;
        auto level1 = openVolume(root, options);
        EXPECT_EQ(level1->info().dims, (Dims3{7, 5, 5}));
        test::expectDoubleEq(level1->info().spacing, glm::dvec3(1.0, 1.5, 4.0));
        test::expectDoubleEq(level1->info().origin, glm::dvec3(-9.75, 20.375, 31.0));
        test::expectValues(*level1, volumeValues({7, 5, 5}, 2));
        expectIoError([&] { openZarrVolume(root, 2); },
                      {root, "no level 2", "0 (13 x 10 x 9), 1 (7 x 5 x 5)"});
    }
}

TEST_F(ZarrReader, MissingChunksAreTheFillValue) {
    ArraySpec a;
    a.fill = 7;
    a.skip = [](int64_t kx, int64_t ky, int64_t kz) { return kx == 1 && ky == 0 && kz == 1; };
    writeArray(path("holes"), a);
    std::vector<double> want;
    for (int64_t z = 0; z < 9; ++z)
        for (int64_t y = 0; y < 10; ++y)
            for (int64_t x = 0; x < 13; ++x)
                want.push_back(x / 5 == 1 && y / 4 == 0 && z / 4 == 1 ? 7.0 : value(x, y, z));
    auto reader = openZarrVolume(path("holes"), 0);
    test::expectValues(*reader, want);
}

TEST_F(ZarrReader, ConvertsFromTheCommandLine) {
    writeOmeImage(path("img.zarr"), 3);
    const auto r = test::runVdiso("convert " + path("img.zarr") + " " + path("img.vdiso") +
                                  " --scale-level 1 --brick 4 --quiet");
    ASSERT_EQ(r.exitCode, 0) << r.output;
    const BrickStoreReader store(path("img.vdiso"));
    EXPECT_EQ(store.volume().spacing, glm::dvec3(1.0, 1.5, 4.0));
    const std::string samples = test::encodeSamples(volumeValues({7, 5, 5}, 2), FileScalar::U16, false);
    EXPECT_EQ(test::compareStoreWithSamples(store, std::vector<unsigned char>(samples.begin(), samples.end())), "");
    const auto wrong = test::runVdiso("convert " + path("img.zarr") + "/0/zarr.json " + path("x.vdiso") + " --scale-level 1");
    EXPECT_NE(wrong.exitCode, 0);
}

// An OME-Zarr at a URL converts to the very store its folder does: over nginx (HTTP, OME-Zarr
// 0.4) and over S3 (signed, the signature checked by botocore; OME-Zarr 0.5), with missing
// chunks the fill value and more chunks in a layer than requests in flight. What cannot be read
// is an error naming the URL, and leaves no output.
TEST_F(ZarrReader, ConvertsFromUrlsToTheSameStore) {
    const Dims3 dims{61, 47, 23};
    auto holes = [](int64_t kx, int64_t ky, int64_t kz) { return (kx + 2 * ky + 3 * kz) % 7 == 0; };
    writeOmeImage(path("srv/bkt/v04.ome.zarr"), 2, dims, holes);
    writeOmeImage(path("srv/bkt/v05.ome.zarr"), 3, dims, holes);
    auto convert = [&](const std::string& env, const std::string& input, const std::string& out,
                       const std::string& extra = "") {
        return test::runCommand(env + VDISO_BINARY + " convert '" + input + "' " + path(out) +
                                " --brick 8 --quiet --connections 3 " + extra);
    };
    for (const char* name : {"v04", "v05"})
        for (const char* level : {"0", "1"}) {
            const auto r = convert("", path("srv/bkt/") + name + ".ome.zarr",
                                   std::string(name) + "_" + level + "_local.vdiso", std::string("--scale-level ") + level);
            ASSERT_EQ(r.exitCode, 0) << r.output;
        }
    {
        test::LoopbackServer nginx = test::startNginx(path("srv"), path(""), path("nginx.log"));
        const std::string url = "http://127.0.0.1:" + std::to_string(nginx.port()) + "/bkt/v04.ome.zarr";
        for (const char* level : {"0", "1"}) {
            SCOPED_TRACE(level);
            const auto r = convert("", url, std::string("v04_") + level + "_http.vdiso", std::string("--scale-level ") + level);
            ASSERT_EQ(r.exitCode, 0) << r.output;
            EXPECT_EQ(test::readFile(path(std::string("v04_") + level + "_http.vdiso")),
                      test::readFile(path(std::string("v04_") + level + "_local.vdiso")));
        }
        // A corrupt chunk is named by its URL; nothing at the URL says so; other formats are
        // read from files only.
        test::writeFile(path("srv/bkt/v04.ome.zarr/0/0.0.1.1.1"), "not a blosc chunk");
        auto r = convert("", url, "bad.vdiso");
        EXPECT_EQ(r.exitCode, 1) << r.output;
        EXPECT_NE(r.output.find(url + "/0/0.0.1.1.1"), std::string::npos) << r.output;
        r = convert("", url + "/../nothing.zarr", "bad.vdiso");
        EXPECT_EQ(r.exitCode, 1) << r.output;
        EXPECT_NE(r.output.find("holds no Zarr metadata"), std::string::npos) << r.output;
        r = convert("", "http://127.0.0.1:" + std::to_string(nginx.port()) + "/bkt/head.nii.gz", "bad.vdiso");
        EXPECT_EQ(r.exitCode, 1) << r.output;
        EXPECT_NE(r.output.find("only as Zarr or OME-Zarr"), std::string::npos) << r.output;
        EXPECT_FALSE(std::filesystem::exists(path("bad.vdiso")));
    }
    // Level 1 only: the S3 server checks each signature in Python, a few ms a request.
    test::LoopbackServer s3 = test::startS3(path("srv"), path("s3.log"));
    for (const char* level : {"1"}) {
        SCOPED_TRACE(level);
        const auto r = convert(test::s3Env(s3.port()), "s3://bkt/v05.ome.zarr", std::string("v05_") + level + "_s3.vdiso",
                               std::string("--scale-level ") + level);
        ASSERT_EQ(r.exitCode, 0) << r.output;
        EXPECT_EQ(test::readFile(path(std::string("v05_") + level + "_s3.vdiso")),
                  test::readFile(path(std::string("v05_") + level + "_local.vdiso")));
    }
    const auto r = convert(test::s3Env(s3.port()) + "AWS_SECRET_ACCESS_KEY=wrong ", "s3://bkt/v05.ome.zarr", "bad.vdiso");
    EXPECT_EQ(r.exitCode, 1) << r.output;
    EXPECT_NE(r.output.find("s3://bkt/v05.ome.zarr/"), std::string::npos) << r.output;
    EXPECT_NE(r.output.find("HTTP 403 (Forbidden): SignatureDoesNotMatch"), std::string::npos) << r.output;
    EXPECT_FALSE(std::filesystem::exists(path("bad.vdiso")));
}

TEST_F(ZarrErrors, CorruptChunkIsNamed) {
    for (Codec codec : {Codec::Blosc, Codec::Zstd, Codec::Gzip, Codec::None}) {
        SCOPED_TRACE(int(codec));
        ArraySpec a;
        a.codec = codec;
        const std::string dir = path("bad" + std::to_string(int(codec)));
        writeArray(dir, a);
        const std::string chunk = dir + "/1.2.0";
        std::vector<unsigned char> bytes = test::readFile(chunk);
        bytes.resize(bytes.size() / 2);  // cut in half
        test::writeFile(chunk, bytes.data(), bytes.size());
        expectIoError(
            [&] {
                auto reader = openZarrVolume(dir, 0);
                test::readAllValues(*reader);
            },
            {chunk});
    }
}

TEST_F(ZarrErrors, UnsupportedAndMalformedMetadataAreNamed) {
    const std::pair<std::string, std::string> cases[] = {
        {R"({"zarr_format": 2, "shape": [9, 10, 13], "chunks": [4, 4, 5], "dtype": "<u2", "compressor": null, "fill_value": 0, "order": "F"})", "order \"F\""},
        {R"({"zarr_format": 2, "shape": [9, 10, 13], "chunks": [4, 4, 5], "dtype": "<i8", "compressor": null, "fill_value": 0, "order": "C"})", "<i8"},
        {R"({"zarr_format": 2, "shape": [9, 10, 13], "chunks": [4, 4, 5], "dtype": "<u2", "compressor": {"id": "lzma"}, "fill_value": 0})", "compressor \"lzma\""},
        {R"({"zarr_format": 2, "shape": [9, 10, 13], "chunks": [4, 4, 5], "dtype": "<u2", "compressor": null, "filters": [{"id": "delta"}]})", "filters"},
        {R"({"zarr_format": 2, "shape": [10, 13], "chunks": [4, 5], "dtype": "<u2", "compressor": null})", "is 2-D"},
        {R"({"zarr_format": 2, "shape": [2, 9, 10, 13], "chunks": [1, 4, 4, 5], "dtype": "<u2", "compressor": null})", "only one time point"},
        {R"({"zarr_format": 2, "shape": [9, 10, 13], "chunks": [4096, 4096, 4096], "dtype": "<u2", "compressor": null})", "1 GiB"},
        {R"({"zarr_format": 2, "shape": [9, 10], "chunks": [4, 4, 5], "dtype": "<u2"})", "differ in length"},
        {R"({"zarr_format": 2, "shape": "big"})", "not an array"},
        {R"({"zarr_format": 2, "shape": [9, 10, 13], "chunks": [4, 4, 5], "dtype": "<u2", "fill_value": "0x7fc00000"})", "fill_value"},
        {R"({"zarr_format": 2, "shape": [9, 10, 13], )", "not valid JSON"},
        // fuzz_zarr's finding, literally: a float zarr_format was converted to int unchecked.
        {R"({"zarr_format": 3333333333333333333333333333333333333333333333333333333333333333333333333333333333333333333332, "shape": [4, 6, 8], "chunks": [2, 4, 4], "dtype": "<u1", "cofilters": null})", "zarr_format is not 2"},
    };
    for (const auto& [json, part] : cases) {
        SCOPED_TRACE(part);
        write("m/.zarray", json);
        expectIoError(
            [&] {
                auto reader = openZarrVolume(path("m"), 0);
                test::readAllValues(*reader);
            },
            {path("m"), part});
    }
    // fuzz_zarr's finding (UBSan, float-cast-overflow): chunks of 5.5e17 elements made a byte
    // count of 6.7e19, converted to an integer for the message.
    write("h/zarr.json", R"({"zarr_format": 3, "node_type": "array", "shape": [9, 10, 13], "data_type": "float64", "chunk_grid": {"name": "regular", "configuration": {"chunk_shape": [550000000, 1000000000, 100]}}, "fill_value": 0, "codecs": [{"name": "bytes", "configuration": {"endian": "little"}}]})");
    expectIoError([&] { openZarrVolume(path("h"), 0); },
                  {path("h"), "550000000 x 1000000000 x 100 samples", "over 2^64", "1 GiB"});
    write("s/zarr.json", R"({"zarr_format": 3, "node_type": "array", "shape": [9, 10, 13], "data_type": "uint16", "chunk_grid": {"name": "regular", "configuration": {"chunk_shape": [9, 10, 13]}}, "fill_value": 0, "codecs": [{"name": "sharding_indexed", "configuration": {}}, {"name": "zstd"}]})");
    expectIoError([&] { openZarrVolume(path("s"), 0); }, {"codecs after sharding_indexed"});
    write("s2/zarr.json", R"({"zarr_format": 3, "node_type": "array", "shape": [9, 10, 13], "data_type": "uint16", "chunk_grid": {"name": "regular", "configuration": {"chunk_shape": [9, 10, 13]}}, "fill_value": 0, "codecs": [{"name": "sharding_indexed", "configuration": {"chunk_shape": [4, 5, 13], "codecs": [{"name": "bytes"}], "index_codecs": [{"name": "bytes"}]}}]})");
    expectIoError([&] { openZarrVolume(path("s2"), 0); }, {"inner chunks 4 x 5 x 13 do not divide its shards 9 x 10 x 13"});
    std::filesystem::create_directories(path("empty"));
    expectIoError([&] { openZarrVolume(path("empty"), 0); }, {"no Zarr metadata"});
    write("p/.zarray", R"({"zarr_format": 2, "shape": [9, 10, 13], "chunks": [4, 4, 5], "dtype": "<u2", "compressor": null})");
    expectIoError([&] { openZarrVolume(path("p"), 1); }, {"plain Zarr array", "no level 1"});
}

TEST_F(ZarrReader, SkipMatchesReadingAcrossChunks) {
    ArraySpec a;  // 9 slices in chunks of 5: skips that end inside, at and past a chunk
    writeArray(path("a"), a);
    test::expectSkipMatchesRead([&] { return openVolume(path("a"), {}); });
}

}  // namespace
}  // namespace vdiso
