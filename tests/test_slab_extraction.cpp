// app/slab_extraction.h: a volume read once in order, a layer of bricks at a time, meshed into
// the mesh the octree makes of it held whole, vertex numbers included.
#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>

#include "app/array_brick_source.h"
#include "app/slab_extraction.h"
#include "core/extract/extract_full.h"
#include "test_util.h"

namespace vdiso {
namespace {

StridedSamples samplesOf(const test::MemoryVolume& v) {
    const int64_t bytes = int64_t(scalarSize(v.info().type));
    StridedSamples s;
    s.data = v.bytes().data();
    s.type = fileScalarOf(v.info().type);
    s.dims = v.info().dims;
    s.strides = {bytes, bytes * s.dims[0], bytes * s.dims[0] * s.dims[1]};
    return s;
}

// A smooth field over the pseudo-random one: surfaces crossing every layer of bricks.
void makeWavy(test::MemoryVolume& v) {
    const Dims3 d = v.info().dims;
    auto* p = reinterpret_cast<uint16_t*>(v.bytes().data());
    for (int64_t z = 0; z < d[2]; ++z)
        for (int64_t y = 0; y < d[1]; ++y)
            for (int64_t x = 0; x < d[0]; ++x)
                p[(z * d[1] + y) * d[0] + x] = uint16_t(3000 + 1000 * (std::sin(z / 5.0) * std::cos(y / 7.0) + std::sin(x / 4.0)) +
                                                        (p[(z * d[1] + y) * d[0] + x] % 50));
}

struct SlabCase {
    int brick, threads;
};

class SlabExtraction : public ::testing::TestWithParam<SlabCase> {};

TEST_P(SlabExtraction, MakesTheMeshOfTheVolumeHeldWhole) {
    const SlabCase c = GetParam();
    test::MemoryVolume volume({37, 29, 75}, ScalarType::U16);
    makeWavy(volume);
    const double iso = 3300.5;
    TriangleMesh whole;
    ArrayBrickSource held(samplesOf(volume), c.brick, volume.info().spacing, c.threads);
    extractOctree(held, {iso, 4, c.threads}, whole);
    ASSERT_GT(whole.triangleCount(), 5000u);

    SlabExtractOptions options;
    options.extract = {iso, 4, c.threads};
    options.brickSize = c.brick;
    size_t reported = 0;
    options.layerDone = [&](const StridedSamples& rows, int64_t firstRow, std::span<const glm::vec3> added) {
        EXPECT_LE(rows.dims[2], c.brick + 3);
        for (const glm::vec3& p : added) {  // every vertex lies in the slices held
            EXPECT_GE(p.z, float(firstRow));
            EXPECT_LE(p.z, float(firstRow + rows.dims[2] - 1));
        }
        reported += added.size();
    };
    TriangleMesh slabs;
    const SlabExtractResult result = extractSlabs(volume, options, slabs);
    EXPECT_EQ(reported, slabs.positions.size());
    EXPECT_EQ(result.stats.triangles, whole.triangleCount());
    EXPECT_EQ(result.stats.vertices, whole.positions.size());
    EXPECT_TRUE(slabs.positions == whole.positions);
    EXPECT_TRUE(slabs.normals == whole.normals);
    EXPECT_TRUE(slabs.indices == whole.indices);
    float lo = INFINITY, hi = -INFINITY;
    for (const BrickRange& r : held.brickRanges()) {
        lo = std::min(lo, r.minValue);
        hi = std::max(hi, r.maxValue);
    }
    EXPECT_EQ(result.range.minValue, lo);
    EXPECT_EQ(result.range.maxValue, hi);
}

INSTANTIATE_TEST_SUITE_P(BricksAndThreads, SlabExtraction,
                         ::testing::Values(SlabCase{8, 1}, SlabCase{8, 2}, SlabCase{16, 2}, SlabCase{32, 1}),
                         [](const auto& p) {
                             return "Brick" + std::to_string(p.param.brick) + "Threads" +
                                    std::to_string(p.param.threads);
                         });

// Runs of layers meshed apart (as a cluster's workers do), each from its first slice on, then
// joined: the mesh of the volume held whole, vertex numbers included, and the values carried.
TEST(SlabExtraction, RunsMeshedApartJoinIntoTheMeshOfTheVolumeHeldWhole) {
    test::MemoryVolume volume({37, 29, 75}, ScalarType::U16);
    makeWavy(volume);
    const double iso = 3300.5;
    TriangleMesh whole;
    ArrayBrickSource held(samplesOf(volume), 8, volume.info().spacing, 2);
    extractOctree(held, {iso, 4, 2}, whole);
    const int64_t runs[][2] = {{0, 3}, {3, 4}, {4, 10}};  // 10 layers of bricks of 8
    std::vector<SlabPart> parts;
    std::vector<std::vector<float>> values;
    for (const auto& run : runs) {
        test::MemoryVolume reader({37, 29, 75}, ScalarType::U16);
        reader.bytes() = volume.bytes();
        reader.skip(std::max<int64_t>(run[0] * 8 - 1, 0));
        SlabExtractOptions options;
        options.extract = {iso, 4, 2};
        options.brickSize = 8;
        std::vector<float>& z = values.emplace_back();
        options.layerDone = [&](const StridedSamples&, int64_t, std::span<const glm::vec3> added) {
            for (const glm::vec3& p : added) z.push_back(p.z);
        };
        parts.push_back(extractSlabPart(reader, options, run[0], run[1]));
        EXPECT_GT(parts.back().border.size(), 0u);
    }
    TriangleMesh joined;
    std::vector<float> z;
    joinSlabParts(parts, values, joined, &z);
    EXPECT_TRUE(joined.positions == whole.positions);
    EXPECT_TRUE(joined.normals == whole.normals);
    EXPECT_TRUE(joined.indices == whole.indices);
    ASSERT_EQ(z.size(), joined.positions.size());
    for (size_t v = 0; v < z.size(); ++v) ASSERT_EQ(z[v], joined.positions[v].z) << v;
}

TEST(SlabExtraction, RangePassAgreesWithTheVolumeHeldWhole) {
    test::MemoryVolume volume({20, 18, 41}, ScalarType::F32);
    ArrayBrickSource held(samplesOf(volume), 8, volume.info().spacing, 1);
    const BrickRange range = sliceRange(volume, 8, 2);
    float lo = INFINITY, hi = -INFINITY;
    for (const BrickRange& r : held.brickRanges()) {
        lo = std::min(lo, r.minValue);
        hi = std::max(hi, r.maxValue);
    }
    EXPECT_EQ(range.minValue, lo);
    EXPECT_EQ(range.maxValue, hi);
}

// A window of rows: the bricks outside it are never active and cannot be acquired.
TEST(SlabExtraction, AWindowHoldsOnlyItsLayersBricks) {
    test::MemoryVolume volume({20, 18, 41}, ScalarType::U16);
    StridedSamples rows = samplesOf(volume);
    rows.dims[2] = 11;  // rows [7, 18) of the 41: layer 1 of bricks of 8 (rows 7 to 17)
    const int64_t bytes = 2 * 20 * 18;
    rows.data = volume.bytes().data() + 7 * bytes;
    ArrayBrickSource window(rows, 7, 41, 8, glm::dvec3(1.0), 1);
    EXPECT_TRUE(window.holdsLayer(1));
    EXPECT_FALSE(window.holdsLayer(0));
    EXPECT_FALSE(window.holdsLayer(2));
    const BrickLayout& layout = window.layout();
    ArrayBrickSource whole(samplesOf(volume), 8, glm::dvec3(1.0), 1);
    for (int64_t id = 0; id < layout.brickCount(); ++id) {
        const BrickRange r = window.brickRanges()[size_t(id)];
        if (layout.brickCoord(id)[2] == 1) {
            EXPECT_EQ(r.minValue, whole.brickRanges()[size_t(id)].minValue);
            EXPECT_EQ(r.maxValue, whole.brickRanges()[size_t(id)].maxValue);
            const BrickHandle a = window.acquire(id), b = whole.acquire(id);
            EXPECT_EQ(0, std::memcmp(a.samples(), b.samples(), size_t(layout.samplesPerBrick()) * 2));
        } else {
            EXPECT_TRUE(r.minValue > r.maxValue) << "brick " << id;
            EXPECT_THROW(window.acquire(id), std::logic_error);
        }
    }
    EXPECT_THROW(ArrayBrickSource(rows, 35, 41, 8, glm::dvec3(1.0), 1), std::logic_error);
}

}  // namespace
}  // namespace vdiso
