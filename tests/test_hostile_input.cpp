// Regression tests for the defect classes of issue 15 (a fuzz and sanitizer probe): each test
// writes the probe's literal input, or the smallest input of the same class, and checks that
// vdiso handles it deliberately: a clean result or a message naming the file, never a crash, a
// hang, a runaway allocation or lost input.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>
#include <string>
#include <vector>

#include "cache/brick_cache.h"
#include "core/extract_full.h"
#include "core/iso.h"
#include "core/mc_tables.h"
#include "io/brick_store.h"
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

}  // namespace
}  // namespace vdiso
