// Regression tests for the defect classes of issue 15 (a fuzz and sanitizer probe): each test
// writes the probe's literal input, or the smallest input of the same class, and checks that
// vdiso handles it deliberately: a clean result or a message naming the file, never a crash, a
// hang, a runaway allocation or lost input.
#include <gtest/gtest.h>

#include <sys/stat.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <limits>
#include <string>
#include <vector>

#include "cache/brick_cache.h"
#include "core/extract/extract_full.h"
#include "core/kernel/iso.h"
#include "core/kernel/mc_tables.h"
#include "io/crc32.h"
#include "io/store/brick_store.h"
#include "io/camera_json.h"
#include "io/error.h"
#include "io/store/store_format.h"
#include "io/store/store_writer.h"
#include "io/text_file.h"
#include "tests/reader_test_util.h"
#include "tests/test_util.h"

namespace vdiso {
namespace {

using test::runVdiso;
using test::ScratchDir;

constexpr float kInf = std::numeric_limits<float>::infinity();
constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();

// A NIfTI-1 single file (.nii) of float64 samples, dims nx x ny x nz, unit spacing.
std::string niftiFloat64(int nx, int ny, int nz, const std::vector<double>& values) {
    std::string bytes(352, '\0');
    auto put = [&](size_t offset, auto v) { std::memcpy(&bytes[offset], &v, sizeof(v)); };
    put(0, int32_t(348));
    const int16_t dims[8] = {3, int16_t(nx), int16_t(ny), int16_t(nz), 1, 1, 1, 1};
    for (int d = 0; d < 8; ++d) put(40 + 2 * size_t(d), dims[d]);
    put(70, int16_t(64));  // DT_FLOAT64
    put(72, int16_t(64));  // bitpix
    for (int d = 0; d < 4; ++d) put(76 + 4 * size_t(d), 1.0f);
    put(108, 352.0f);  // vox_offset
    std::memcpy(&bytes[344], "n+1", 4);
    bytes.append(reinterpret_cast<const char*>(values.data()), values.size() * sizeof(double));
    return bytes;
}

// Triangles of every cell of the volume by brute force: the count any full extraction must give.
uint64_t bruteForceTriangles(const std::vector<float>& v, const Dims3& d, double iso) {
    uint64_t triangles = 0;
    for (int64_t z = 0; z + 1 < d[2]; ++z)
        for (int64_t y = 0; y + 1 < d[1]; ++y)
            for (int64_t x = 0; x + 1 < d[0]; ++x) {
                float corners[8];
                for (int c = 0; c < 8; ++c)
                    corners[c] = v[size_t(((z + kCornerOffset[c][2]) * d[1] + y + kCornerOffset[c][1]) *
                                              d[0] + x + kCornerOffset[c][0])];
                triangles += mcTriangleCase(mcCaseIndex(corners, iso)).triangleCount;
            }
    return triangles;
}

void expectFiniteMesh(const TriangleMesh& mesh) {
    for (size_t i = 0; i < mesh.positions.size(); ++i)
        for (int a = 0; a < 3; ++a) {
            ASSERT_TRUE(std::isfinite(mesh.positions[i][a])) << "vertex " << i;
            ASSERT_TRUE(std::isfinite(mesh.normals[i][a])) << "normal " << i;
        }
}

// Class 1: a NIfTI float64 sample below the float range becomes -inf; converting it wrote far
// outside the histogram (bin int(NaN)). One sample is enough.
TEST(HostileInput, NiftiFloat64BelowFloatRangeBecomesMinusInfinity) {
    ScratchDir dir;
    std::vector<double> values(4 * 3 * 2);
    for (size_t i = 0; i < values.size(); ++i) values[i] = double(i);
    values[5] = -1e300;
    test::writeFile(dir.file("v.nii"), niftiFloat64(4, 3, 2, values));
    const auto r = runVdiso("convert " + dir.file("v.nii") + " " + dir.file("v.vdiso"));
    ASSERT_EQ(r.exitCode, 0) << r.output;
    const BrickStoreReader store(dir.file("v.vdiso"));
    EXPECT_EQ(store.header().valueMin, -double(kInf));
    EXPECT_EQ(store.header().valueMax, 23.0);
    const ValueHistogram& h = store.histogram();
    EXPECT_EQ(h.lo, 0.0);  // the finite samples' range
    EXPECT_EQ(h.hi, 23.0);
    uint64_t total = 0;
    for (uint64_t c : h.counts) total += c;
    EXPECT_EQ(total, values.size());
    EXPECT_EQ(h.counts[0], 2u);  // -inf and 0
}

// Class 1: NaN, +inf and -inf samples in a float volume, each where the old rules went wrong:
// a NaN (below every isovalue) among samples above it, in a brick whose range ignored it; +inf
// among samples below; -inf among samples above. The store's ranges must agree with the cell
// test (the extraction through them gives the brute-force triangle count), and nothing in the
// store or the surface is NaN.
TEST(HostileInput, NonFiniteFloatSamplesAreRangedBinnedAndExtractedByOneRule) {
    ScratchDir dir;
    const Dims3 d{9, 9, 9};
    std::vector<float> v(size_t(d[0] * d[1] * d[2]));
    auto at = [&](int x, int y, int z) -> float& { return v[size_t((z * d[1] + y) * d[0] + x)]; };
    for (int z = 0; z < 9; ++z)
        for (int y = 0; y < 9; ++y)
            for (int x = 0; x < 9; ++x) at(x, y, z) = float(x + y + z);
    at(8, 8, 8) = kNaN;   // the far corner: every neighbour is above 10.5
    at(7, 6, 8) = kNaN;
    at(0, 8, 0) = kInf;   // neighbours below
    at(8, 0, 8) = -kInf;  // neighbours above
    at(4, 3, 2) = kNaN;   // near the surface
    test::writeFile(dir.file("v.raw"), v.data(), v.size() * sizeof(float));
    const auto r = runVdiso("convert " + dir.file("v.raw") + " " + dir.file("v.vdiso") +
                            " --dims 9,9,9 --type f32 --brick 4");
    ASSERT_EQ(r.exitCode, 0) << r.output;
    const BrickStoreReader store(dir.file("v.vdiso"));
    EXPECT_EQ(store.header().valueMin, -double(kInf));
    EXPECT_EQ(store.header().valueMax, double(kInf));
    for (const BrickEntry& e : store.index()) {
        EXPECT_FALSE(std::isnan(e.minValue));
        EXPECT_FALSE(std::isnan(e.maxValue));
    }
    const ValueHistogram& h = store.histogram();
    EXPECT_EQ(h.lo, 0.0);
    EXPECT_TRUE(std::isfinite(h.hi));
    EXPECT_GE(h.hi, 23.0);
    uint64_t total = 0;
    for (uint64_t c : h.counts) total += c;
    EXPECT_EQ(total, v.size() - 3);  // NaN counted nowhere

    for (const double iso : {10.5, 15.5, 3.0}) {
        BrickCache cache(store, 64 * store.brickBytes());
        TriangleMesh mesh;
        extractOctree(cache, {iso, 2}, mesh);
        EXPECT_EQ(mesh.triangleCount(), bruteForceTriangles(v, d, iso)) << "iso " << iso;
        expectFiniteMesh(mesh);
    }
}

TEST(HostileInput, CrossingFractionIsInTheEdgeForNonFiniteEnds) {
    EXPECT_EQ(crossingFraction(-kInf, 5.0, 3.0), 1.0);
    EXPECT_EQ(crossingFraction(5.0, -kInf, 3.0), 0.0);
    EXPECT_EQ(crossingFraction(kInf, 1.0, 3.0), 1.0);
    EXPECT_EQ(crossingFraction(kNaN, 5.0, 3.0), 1.0);
    EXPECT_EQ(crossingFraction(kNaN, kInf, 3.0), 0.5);
    EXPECT_EQ(crossingFraction(1.0, 5.0, 2.0), 0.25);
    EXPECT_EQ(rangeValue(kNaN), -kInf);
    EXPECT_EQ(rangeValue(2.5f), 2.5f);
    EXPECT_THROW(requireFiniteIso(kNaN), std::invalid_argument);
}

// A small valid store, and ways to make it hostile with valid checksums (recomputed after each
// patch, so the checks behind them are reached).
class HostileStore : public ::testing::Test {
protected:
    void SetUp() override { makeStore({21, 13, 12}, ScalarType::U16, 8); }
    void makeStore(const Dims3& dims, ScalarType type, int brickSize) {
        test::MemoryVolume volume(dims, type);
        StoreWriteOptions o;
        o.brickSize = brickSize;
        o.overwrite = true;
        path = dir.file("good.vdiso");
        writeBrickStore(volume, path, o);
        bytes = test::readFile(path);
        header = BrickStoreReader(path).header();
    }
    template <class T>
    void patchHeader(size_t offset, T value) {
        std::memcpy(bytes.data() + offset, &value, sizeof(T));
        const uint32_t crc = crc32Of(bytes.data(), 160);
        std::memcpy(bytes.data() + 160, &crc, 4);
    }
    // `offset` within the raw index (packed again after).
    template <class T>
    void patchIndex(size_t offset, T value) {
        bytes = test::rewriteStoreIndex(bytes, [&](std::vector<unsigned char>& index) {
            std::memcpy(index.data() + offset, &value, sizeof(T));
            const uint32_t crc = crc32Of(index.data(), index.size() - 4);
            std::memcpy(index.data() + index.size() - 4, &crc, 4);
        });
    }
    // The message opening the patched store (and reading every brick) gives; "" if none. Any
    // exception other than IoError is a failure: every refusal must name the file.
    std::string openError() { return test::storeOpenError(dir.file("bad.vdiso"), bytes); }
    ScratchDir dir;
    std::string path;
    std::vector<unsigned char> bytes;
    StoreHeader header;
};

// Class 2: raw dimensions whose product wraps 64 bits (2^93 samples) passed the size check
// with an empty file, then allocated about 24 GB.
TEST(HostileInput, RawDimensionsWhoseProductWrapsAreRefused) {
    ScratchDir dir;
    test::writeFile(dir.file("empty.raw"), "");
    const auto r = runVdiso("convert " + dir.file("empty.raw") + " " + dir.file("out.vdiso") +
                            " --dims 2147483648,2147483648,2147483648 --type f32");
    EXPECT_NE(r.exitCode, 0);
    EXPECT_NE(r.output.find("empty.raw"), std::string::npos) << r.output;
    EXPECT_NE(r.output.find("at most 2^48 samples"), std::string::npos) << r.output;
    EXPECT_FALSE(std::filesystem::exists(dir.file("out.vdiso")));
    // Within the per-axis limit but over the total, without wrapping.
    EXPECT_NE(volumeDimsProblem({1 << 20, 1 << 20, 1 << 9}), "");
    EXPECT_EQ(volumeDimsProblem({1 << 20, 1 << 20, 1 << 8}), "");
    EXPECT_NE(volumeDimsProblem({(int64_t(1) << 31) + 1, 2, 2}), "");
    VolumeInfo huge;
    huge.dims = {int64_t(1) << 31, int64_t(1) << 31, int64_t(1) << 31};
    EXPECT_THROW(huge.sampleCount(), std::overflow_error);
    EXPECT_THROW(BrickLayout(huge.dims, 2).brickCount(), std::overflow_error);
    EXPECT_THROW(store_format::indexBytes(uint64_t(1) << 60), std::overflow_error);
}

// Class 2: a store whose dimensions make the brick count wrap (2^31 x 2^31 x 2^17 samples,
// with the header's brick count set to the wrapped product) opened or failed with a bare
// vector::_M_default_append.
TEST_F(HostileStore, DimensionsWhoseBrickCountWrapsAreRefused) {
    const int64_t dims[3] = {int64_t(1) << 31, int64_t(1) << 31, int64_t(1) << 17};
    for (int a = 0; a < 3; ++a) patchHeader<uint64_t>(16 + 8 * size_t(a), uint64_t(dims[a]));
    // ceil((2^31 - 1) / 8)^2 * ceil((2^17 - 1) / 8) = 2^70 bricks, which wraps to 0, and the
    // index size of 0 bricks.
    patchHeader<uint64_t>(112, 0);
    patchHeader<uint64_t>(128, 2100);
    const std::string msg = openError();
    EXPECT_NE(msg.find("bad.vdiso"), std::string::npos) << msg;
    EXPECT_NE(msg.find("at most 2^48 samples"), std::string::npos) << msg;
}

// Class 2: an index offset near 2^64 made offset + size wrap past the file-size check.
TEST_F(HostileStore, IndexOffsetThatWrapsIsRefused) {
    patchHeader<uint64_t>(120, ~uint64_t(0) - 100);
    const std::string msg = openError();
    EXPECT_NE(msg.find("bad.vdiso"), std::string::npos) << msg;
    EXPECT_NE(msg.find("index is missing or truncated"), std::string::npos) << msg;
}

// Class 2 (and 11): an entry offset near 2^64 made offset + stored size wrap below the index.
// Bricks stored raw of 19^3 f32 (27,436 bytes) at offset 2^64 - 8192 end at byte 19,244.
TEST_F(HostileStore, EntryOffsetThatWrapsIsRefused) {
    makeStore({40, 20, 20}, ScalarType::F32, 16);
    patchIndex<uint64_t>(16 + 32 * 3, ~uint64_t(0) - 8191);  // brick 3, 4096-aligned
    const std::string msg = openError();
    EXPECT_NE(msg.find("bad.vdiso"), std::string::npos) << msg;
    EXPECT_NE(msg.find("index entry of brick 3 is invalid"), std::string::npos) << msg;
}

// Class 3: 131073 x 2 x 2 samples with --brick 2 make 65,536 bricks along x, one more than the
// min/max tree indexes; extract aborted on a VDISO_CHECK. Refused at convert, before any output.
TEST(HostileInput, MoreThan65535BricksOnAnAxisAreRefusedAtConvert) {
    ScratchDir dir;
    test::writeFile(dir.file("long.raw"), std::string(131073 * 2 * 2, '\x07'));
    const auto r = runVdiso("convert " + dir.file("long.raw") + " " + dir.file("long.vdiso") +
                            " --dims 131073,2,2 --type u8 --brick 2");
    EXPECT_NE(r.exitCode, 0);
    EXPECT_NE(r.output.find("long.raw"), std::string::npos) << r.output;
    EXPECT_NE(r.output.find("65536 bricks along x"), std::string::npos) << r.output;
    EXPECT_NE(r.output.find("use larger bricks"), std::string::npos) << r.output;
    EXPECT_FALSE(std::filesystem::exists(dir.file("long.vdiso")));
    // One brick fewer is within the limit, and extracts.
    test::writeFile(dir.file("ok.raw"), std::string(131071 * 2 * 2, '\x07'));
    const auto ok = runVdiso("convert " + dir.file("ok.raw") + " " + dir.file("ok.vdiso") +
                             " --dims 131071,2,2 --type u8 --brick 2");
    ASSERT_EQ(ok.exitCode, 0) << ok.output;
    const BrickStoreReader store(dir.file("ok.vdiso"));
    EXPECT_EQ(store.layout().brickCounts[0], 65535);
}

// Class 3, at open: a store (valid checksums) whose header says 131073 x 2 x 2 in bricks of 2.
TEST_F(HostileStore, MoreThan65535BricksOnAnAxisAreRefusedAtOpen) {
    patchHeader<uint64_t>(16, 131073);
    patchHeader<uint64_t>(24, 2);
    patchHeader<uint64_t>(32, 2);
    patchHeader<uint32_t>(92, 2);
    const std::string msg = openError();
    EXPECT_NE(msg.find("bad.vdiso"), std::string::npos) << msg;
    EXPECT_NE(msg.find("65536 bricks along x"), std::string::npos) << msg;
}

// Output of `command` run under a pseudo-terminal (util-linux script), at most `limit` bytes.
std::string runOnTerminal(const std::string& command, size_t limit) {
    return test::runCommand("timeout 60 script -qec '" + command + "' /dev/null 2>&1 | head -c " +
                            std::to_string(limit)).output;
}

// Class 6: on a terminal, extract --threads 2 with an isovalue outside the volume's range
// reported progress 0/0 = NaN, and the bar wrote 2 GiB of spaces.
TEST(HostileInput, ProgressOfNothingToDoDrawsOneBar) {
    if (std::system("command -v script >/dev/null 2>&1") != 0) GTEST_SKIP() << "no script(1)";
    ScratchDir dir;
    test::writeFile(dir.file("v.raw"), std::string(20 * 20 * 20, '\x07'));
    ASSERT_EQ(runVdiso("convert " + dir.file("v.raw") + " " + dir.file("v.vdiso") +
                       " --dims 20,20,20 --type u8").exitCode, 0);
    const std::string out = runOnTerminal(std::string(VDISO_BINARY) + " extract " +
                                              dir.file("v.vdiso") + " --iso 200 --threads 2 -o " +
                                              dir.file("v.ply"), 1 << 20);
    EXPECT_LT(out.size(), 4096u) << out.substr(0, 400);
    EXPECT_NE(out.find("100%"), std::string::npos) << out.substr(0, 400);
}

// Class 10: --camera /dev/zero and --path /dev/zero read the whole (endless) file into memory.
TEST(HostileInput, CameraAndPathFilesAreReadWithABound) {
    ScratchDir dir;
    test::writeFile(dir.file("v.raw"), std::string(10 * 10 * 10, '\x07'));
    ASSERT_EQ(runVdiso("convert " + dir.file("v.raw") + " " + dir.file("v.vdiso") +
                       " --dims 10,10,10 --type u8").exitCode, 0);
    for (const std::string flag : {"--camera", "--path"}) {
        const std::string rest = flag == "--camera" ? " --method sage -o " + dir.file("v.ply")
                                                    : " --png " + dir.file("f_%04d.png");
        const auto r = runVdiso("extract " + dir.file("v.vdiso") + " --iso 3 " + flag +
                                " /dev/zero" + rest);
        EXPECT_NE(r.exitCode, 0) << flag;
        EXPECT_NE(r.output.find("/dev/zero: is larger than 16777216 bytes"), std::string::npos)
            << flag << ": " << r.output;
    }
    // A file of the bound plus one byte, and the bound's own size is read (and parsed).
    test::writeFile(dir.file("big.json"), std::string((size_t(16) << 20) + 1, ' '));
    EXPECT_THROW(readBoundedText(dir.file("big.json"), size_t(16) << 20, "a camera file"), IoError);
    EXPECT_EQ(readBoundedText(dir.file("big.json"), (size_t(16) << 20) + 1, "x").size(),
              (size_t(16) << 20) + 1);
}

// Class 11: spacing and origin were never checked at open: 0 (NaN normals), negative, NaN, inf.
TEST_F(HostileStore, SpacingAndOriginOutOfRangeAreRefused) {
    const auto good = bytes;
    const double nan = std::numeric_limits<double>::quiet_NaN();
    const double inf = std::numeric_limits<double>::infinity();
    for (const double spacing : {0.0, -1.0, nan, inf, -inf}) {
        bytes = good;
        patchHeader<double>(40 + 8, spacing);  // spacing along y
        const std::string msg = openError();
        EXPECT_NE(msg.find("bad.vdiso: header's spacing"), std::string::npos)
            << spacing << ": " << msg;
        EXPECT_NE(msg.find("along y"), std::string::npos) << spacing << ": " << msg;
    }
    for (const double origin : {nan, inf, -inf}) {
        bytes = good;
        patchHeader<double>(64 + 16, origin);  // origin along z
        const std::string msg = openError();
        EXPECT_NE(msg.find("bad.vdiso: header's origin along z"), std::string::npos)
            << origin << ": " << msg;
    }
    bytes = good;
    patchHeader<double>(64, 1e308);  // finite, but the far end is not
    patchHeader<double>(40, 1e307);
    EXPECT_NE(openError().find("far end"), std::string::npos);
    bytes = good;
    EXPECT_EQ(openError(), "");  // the unpatched store opens: the checks above are the cause
}

// Class 11: NaN value ranges (header, brick entry, histogram) were accepted at open.
TEST_F(HostileStore, NaNRangesAreRefused) {
    const auto good = bytes;
    const double nan = std::numeric_limits<double>::quiet_NaN();
    patchHeader<double>(136, nan);
    EXPECT_NE(openError().find("bad.vdiso: header's value range"), std::string::npos);
    bytes = good;
    patchHeader<double>(144, -1e9);  // max below min
    EXPECT_NE(openError().find("bad.vdiso: header's value range"), std::string::npos);
    for (const size_t field : {16u, 20u}) {  // entry min, max
        bytes = good;
        patchIndex<float>(16 + 32 * 5 + field, kNaN);
        const std::string msg = openError();
        EXPECT_NE(msg.find("bad.vdiso: index entry of brick 5 is invalid"), std::string::npos)
            << field << ": " << msg;
    }
    const size_t histogram = 16 + 32 * BrickStoreReader(path).index().size();
    for (const size_t field : {0u, 8u}) {  // histogram lo, hi
        bytes = good;
        patchIndex<double>(histogram + field, nan);
        EXPECT_NE(openError().find("bad.vdiso: index histogram is invalid"), std::string::npos);
    }
}

// Class 7: --force replaced the input itself when the output named it differently. Each case
// must be refused with the output named, and leave the input's bytes as they were.
TEST(HostileInput, ForceNeverReplacesTheInput) {
    ScratchDir dir;
    const std::string raw(4 * 3 * 2, '\x05');
    test::writeFile(dir.file("vol.raw"), raw);
    std::filesystem::create_symlink(dir.file("vol.raw"), dir.file("link.raw"));
    test::writeFile(dir.file("vol.nhdr"), "NRRD0004\ntype: uint8\ndimension: 3\nsizes: 4 3 2\n"
                                          "encoding: raw\ndata file: vol.raw\n\n");
    const std::string rawArgs = " --dims 4,3,2 --type u8 --force";
    const std::string d = dir.path().string();
    struct Case {
        std::string input, output, args;
    };
    const Case cases[] = {
        {d + "/vol.raw", d + "/./vol.raw", rawArgs},   // the same file, another spelling
        {d + "/link.raw", d + "/vol.raw", rawArgs},    // the input is a link to the output
        {d + "/vol.raw", d + "/link.raw", rawArgs},    // the output is a link to the input
        {d + "/vol.nhdr", d + "/vol.raw", " --force"}, // the header's data file is the output
    };
    for (const Case& c : cases) {
        const auto r = runVdiso("convert " + c.input + " " + c.output + c.args);
        EXPECT_NE(r.exitCode, 0) << c.input << " -> " << c.output;
        EXPECT_NE(r.output.find(c.output + ": is the input"), std::string::npos)
            << c.input << " -> " << c.output << ": " << r.output;
        const auto bytes = test::readFile(dir.file("vol.raw"));
        EXPECT_EQ(std::string(bytes.begin(), bytes.end()), raw) << c.input << " -> " << c.output;
        EXPECT_TRUE(std::filesystem::is_symlink(dir.file("link.raw")));
    }
    // Another file is replaced as before.
    test::writeFile(dir.file("other.vdiso"), "old");
    EXPECT_EQ(runVdiso("convert " + dir.file("vol.raw") + " " + dir.file("other.vdiso") + rawArgs)
                  .exitCode, 0);
    EXPECT_NO_THROW(BrickStoreReader(dir.file("other.vdiso")));
}

// Class 7: as root, --force renamed over a device (/dev/null became a regular file). A FIFO
// stands in for the device: any non-regular file, directly or through a link, is refused.
TEST(HostileInput, ForceNeverReplacesANonRegularFile) {
    ScratchDir dir;
    test::writeFile(dir.file("vol.raw"), std::string(8, '\x05'));
    ASSERT_EQ(::mkfifo(dir.file("fifo").c_str(), 0644), 0);
    std::filesystem::create_symlink(dir.file("fifo"), dir.file("fifo-link"));
    for (const std::string out : {"fifo", "fifo-link"}) {
        const auto r = runVdiso("convert " + dir.file("vol.raw") + " " + dir.file(out) +
                                " --dims 2,2,2 --type u8 --force");
        EXPECT_NE(r.exitCode, 0) << out;
        EXPECT_NE(r.output.find(dir.file(out) + ": is not a regular file"), std::string::npos)
            << r.output;
        EXPECT_TRUE(std::filesystem::is_fifo(dir.file("fifo")));
    }
    EXPECT_TRUE(std::filesystem::is_symlink(dir.file("fifo-link")));
}

// Class 5: NRRD 'line skip' over an endless stream (data file /dev/zero, which has no newline)
// looped forever, and SIGINT was seen only by the progress bar. It must stop within a second.
TEST(HostileInput, LineSkipOverAnEndlessStreamYieldsToCtrlC) {
    ScratchDir dir;
    test::writeFile(dir.file("endless.nhdr"), "NRRD0004\ntype: uint8\ndimension: 3\nsizes: 4 3 2\n"
                                              "encoding: raw\nline skip: 1\ndata file: /dev/zero\n\n");
    // The shell starts the conversion, interrupts it after 0.5 s, and reports its exit code and
    // how long the wait after the signal took; a hard limit kills it if it ignores the signal.
    const std::string script =
        "timeout -s KILL 20 sh -c '" + std::string(VDISO_BINARY) + " convert " +
        dir.file("endless.nhdr") + " " + dir.file("out.vdiso") +
        " & pid=$!; sleep 0.5; kill -INT $pid; start=$(date +%s%N); wait $pid; rc=$?; "
        "echo; echo rc=$rc ms=$(( ($(date +%s%N) - start) / 1000000 ))' 2>&1";
    std::string out;
    FILE* pipe = ::popen(script.c_str(), "r");
    ASSERT_NE(pipe, nullptr);
    char buf[4096];
    size_t n;
    while ((n = std::fread(buf, 1, sizeof buf, pipe)) > 0) out.append(buf, n);
    ::pclose(pipe);
    EXPECT_NE(out.find("rc=130"), std::string::npos) << out;
    EXPECT_NE(out.find("/dev/zero: interrupted"), std::string::npos) << out;
    const size_t ms = out.find("ms=");
    ASSERT_NE(ms, std::string::npos) << out;
    EXPECT_LT(std::stoi(out.substr(ms + 3)), 1000) << out;
    EXPECT_FALSE(std::filesystem::exists(dir.file("out.vdiso")));
}

// Class 9: a JSON number beyond double's range (1e400) gave nlohmann's own tagged message, and a
// 'data file' name holding a NUL byte gave an empty message. Each must name the file in words.
TEST(HostileInput, MessagesNameTheFileForJsonOverflowAndNulInDataFile) {
    ScratchDir dir;
    test::writeFile(dir.file("cam.json"),
                    R"({"eye": [1e400, 0, 0], "target": [0, 0, 0], "up": [0, 1, 0], "fov": 30})");
    try {
        readCameraJson(dir.file("cam.json"), 64, 64);
        ADD_FAILURE() << "1e400 accepted";
    } catch (const IoError& e) {
        const std::string msg = e.what();
        EXPECT_EQ(msg.rfind(dir.file("cam.json") + ": not valid JSON: ", 0), 0u) << msg;
        EXPECT_EQ(msg.find("[json."), std::string::npos) << msg;
    }
    const std::string header = std::string("NRRD0004\ntype: uint8\ndimension: 3\nsizes: 2 2 2\n"
                                           "encoding: raw\ndata file: a") + '\0' + "b.raw\n\n";
    test::writeFile(dir.file("nul.nhdr"), header);
    const auto r = runVdiso("convert " + dir.file("nul.nhdr") + " " + dir.file("nul.vdiso"));
    EXPECT_NE(r.exitCode, 0);
    EXPECT_NE(r.output.find(dir.file("nul.nhdr") + ": 'data file' name holds a NUL byte"),
              std::string::npos) << r.output;
}

// Class 9: `vdiso compare` on a directory said "basic_filebuf::underflow error reading the
// file", naming nothing; an endless file was read whole.
TEST(HostileInput, PngReadsNameTheFileAndAreBounded) {
    ScratchDir dir;
    std::filesystem::create_directories(dir.file("pictures"));
    const auto r = runVdiso("compare " + dir.file("pictures") + " " + dir.file("pictures"));
    EXPECT_EQ(r.exitCode, 1) << r.output;
    EXPECT_NE(r.output.find(dir.file("pictures") + ": "), std::string::npos) << r.output;
    EXPECT_EQ(r.output.find("basic_filebuf"), std::string::npos) << r.output;
    const auto endless = runVdiso("compare /dev/zero /dev/zero");
    EXPECT_EQ(endless.exitCode, 1) << endless.output;
    EXPECT_NE(endless.output.find("/dev/zero: "), std::string::npos) << endless.output;
}

// Output of a shell command line (stderr with stdout).
std::string runShell(const std::string& line) { return test::runCommand(line).output; }

// Class 4: the converter allocated its ring of 2B+3 slices before reading a sample: a real
// 4096 x 4096 x 2 volume (32 MiB) took 67 slices, 1.1 GB. The ring is now the volume's depth
// when that is smaller: under a 768 MiB address-space limit the conversion succeeds.
TEST(HostileInput, ConversionMemoryFollowsTheVolumesDepth) {
    if (VDISO_UNDER_ASAN) GTEST_SKIP() << "an address-space limit and AddressSanitizer exclude each other";
    ScratchDir dir;
    test::writeFile(dir.file("flat.raw"), std::string(size_t(4096) * 4096 * 2, '\x09'));
    const std::string out = runShell("ulimit -v 786432; " + std::string(VDISO_BINARY) +
                                     " convert " + dir.file("flat.raw") + " " +
                                     dir.file("flat.vdiso") + " --dims 4096,4096,2 --type u8; "
                                     "echo rc=$?");
    EXPECT_NE(out.find("rc=0"), std::string::npos) << out;
    EXPECT_NO_THROW(BrickStoreReader(dir.file("flat.vdiso")));
}

// Class 4: a 209-byte gzip NRRD header asked for 17.9 GB before reading a sample. Under an
// address-space limit the refusal is clean and names the file (never a bare std::bad_alloc);
// without one, the data ends and that is said.
TEST(HostileInput, GzipHeaderPromisingHugeSlicesFailsCleanly) {
    ScratchDir dir;
    const std::string header = "NRRD0004\ntype: uint16\ndimension: 3\nsizes: 16384 16384 64\n"
                               "endian: little\nencoding: gzip\n\n";
    test::writeFile(dir.file("huge.nrrd"), header + test::gzipBytes(std::string(1000, '\0')));
    for (const std::string limit : {"ulimit -v 4194304; ", ""}) {
        if (VDISO_UNDER_ASAN && !limit.empty()) continue;  // its shadow needs the address space
        const std::string out = runShell(limit + std::string(VDISO_BINARY) + " convert " +
                                         dir.file("huge.nrrd") + " " + dir.file("huge.vdiso") +
                                         "; echo rc=$?");
        EXPECT_NE(out.find("rc=1"), std::string::npos) << limit << out;
        EXPECT_NE(out.find("huge.nrrd: "), std::string::npos) << limit << out;
        EXPECT_EQ(out.find("bad_alloc"), std::string::npos) << limit << out;
        EXPECT_FALSE(std::filesystem::exists(dir.file("huge.vdiso")));
    }
}

// Class 8: SIGKILL (or a crash, or the OOM killer) left OUTPUT.partial.<pid>.<n> files that
// nothing removed. The output is now unnamed until committed: killed mid-conversion (its gzip
// input stalled on a FIFO after the first slices), vdiso leaves nothing in the directory, and
// shows nothing there while it runs.
TEST(HostileInput, KilledConversionLeavesNoPartialFile) {
    ScratchDir dir;
    const std::string header = "NRRD0004\ntype: uint8\ndimension: 3\nsizes: 64 64 64\n"
                               "encoding: gzip\ndata file: data.fifo\n\n";
    test::writeFile(dir.file("v.nhdr"), header);
    test::writeFile(dir.file("part.gz"), test::gzipBytes(std::string(64 * 64 * 64, '\x03')).substr(0, 200));
    ASSERT_EQ(::mkfifo(dir.file("data.fifo").c_str(), 0644), 0);
    std::filesystem::create_directory(dir.file("out"));
    const std::string d = dir.path().string();
    const std::string out = runShell(
        "cd " + d + " && { (cat part.gz; sleep 10) > data.fifo 2>/dev/null & w=$!; " + VDISO_BINARY +
        " convert v.nhdr out/v.vdiso --quiet & p=$!; sleep 1; echo during: $(ls out); "
        "kill -0 $p && echo still running; kill -KILL $p; wait $p; kill $w; echo after: $(ls out); }");
    EXPECT_NE(out.find("still running"), std::string::npos) << out;  // killed mid-conversion
    EXPECT_NE(out.find("during:\n"), std::string::npos) << out;
    EXPECT_NE(out.find("after:\n"), std::string::npos) << out;
}

}  // namespace
}  // namespace vdiso
