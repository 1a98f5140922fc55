#include "io/readers/vdb_reader.h"

#include <gtest/gtest.h>
#include <openvdb/io/File.h>
#include <openvdb/openvdb.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include <unistd.h>

#include "io/error.h"
#include "tests/reader_test_util.h"
#include "tests/test_util.h"

namespace vdiso {
namespace {

// A file in the temporary directory, removed when the test ends.
class TempFile {
public:
    explicit TempFile(const std::string& stem) {
        const auto* test = ::testing::UnitTest::GetInstance()->current_test_info();
        mPath = (std::filesystem::temp_directory_path() /
                 ("vdiso_" + std::string(test->name()) + "_" + std::to_string(getpid()) + stem))
                    .string();
    }
    ~TempFile() { std::remove(mPath.c_str()); }
    const std::string& path() const { return mPath; }

private:
    std::string mPath;
};

void writeGrids(const std::string& path, const openvdb::GridPtrVec& grids) {
    openvdb::initialize();
    openvdb::io::File(path).write(grids);
}

template <class GridT>
typename GridT::Ptr makeGrid(const std::string& name, typename GridT::ValueType background,
                             double voxelSize = 1.0) {
    openvdb::initialize();
    auto grid = GridT::create(background);
    grid->setName(name);
    grid->setTransform(openvdb::math::Transform::createLinearTransform(voxelSize));
    return grid;
}

std::vector<float> readAll(SliceReader& reader, const std::vector<int64_t>& slabs) {
    const VolumeInfo& info = reader.info();
    std::vector<float> values(size_t(info.sampleCount()));
    int64_t z = 0;
    for (int64_t count : slabs) {
        reader.read(values.data() + size_t(z * info.sliceSamples()), count);
        z += count;
    }
    EXPECT_EQ(z, info.dims[2]);
    reader.finish();
    return values;
}

// What() of the IoError the call throws, or "" if it throws none.
template <class F>
std::string ioErrorOf(F&& f) {
    try {
        f();
    } catch (const IoError& e) {
        return e.what();
    }
    return "";
}

// The usual test input: "density" with three active voxels spanning x 1..4, y 2..6, z 3..5 and
// background 2.5, voxel size 0.5; and a second grid "other".
void writeDensityAndOther(const std::string& path) {
    auto density = makeGrid<openvdb::FloatGrid>("density", 2.5f, 0.5);
    auto acc = density->getAccessor();
    acc.setValue(openvdb::Coord(1, 2, 3), 7.0f);
    acc.setValue(openvdb::Coord(4, 6, 5), -1.0f);
    acc.setValue(openvdb::Coord(2, 3, 4), 3.0f);
    auto other = makeGrid<openvdb::FloatGrid>("other", 0.0f);
    other->getAccessor().setValue(openvdb::Coord(-3, -3, -3), 1.0f);
    other->getAccessor().setValue(openvdb::Coord(0, 0, 0), 2.0f);
    writeGrids(path, {density, other});
}

TEST(VdbReader, ReadsTheActiveBoundingBox) {
    TempFile file(".vdb");
    writeDensityAndOther(file.path());
    auto reader = openVdbVolume(file.path(), "density");
    const VolumeInfo& info = reader->info();
    EXPECT_EQ(info.dims, (Dims3{4, 5, 3}));
    EXPECT_EQ(info.type, ScalarType::F32);
    EXPECT_EQ(info.spacing, glm::dvec3(0.5, 0.5, 0.5));
    EXPECT_EQ(info.origin, glm::dvec3(0.5, 1.0, 1.5));  // index (1, 2, 3) in world units
    const std::vector<float> v = readAll(*reader, {3});
    auto at = [&](int x, int y, int z) { return v[size_t(((z - 3) * 5 + (y - 2)) * 4 + (x - 1))]; };
    EXPECT_EQ(at(1, 2, 3), 7.0f);
    EXPECT_EQ(at(4, 6, 5), -1.0f);
    EXPECT_EQ(at(2, 3, 4), 3.0f);
    size_t background = 0;
    for (float value : v) background += value == 2.5f;
    EXPECT_EQ(background, v.size() - 3);
}

TEST(VdbReader, SkipMatchesReading) {
    TempFile file(".vdb");
    writeDensityAndOther(file.path());
    test::expectSkipMatchesRead([&] { return openVdbVolume(file.path(), "density"); });
}

TEST(VdbReader, SelectsTheGridByName) {
    TempFile file(".vdb");
    writeDensityAndOther(file.path());
    auto reader = openVdbVolume(file.path(), "other");
    EXPECT_EQ(reader->info().dims, (Dims3{4, 4, 4}));
    EXPECT_EQ(reader->info().spacing, glm::dvec3(1.0, 1.0, 1.0));
    EXPECT_EQ(reader->info().origin, glm::dvec3(-3.0, -3.0, -3.0));
    const std::vector<float> v = readAll(*reader, {4});
    EXPECT_EQ(v.front(), 1.0f);
    EXPECT_EQ(v.back(), 2.0f);
    EXPECT_EQ(v[1], 0.0f);
}

TEST(VdbReader, EmptyNameTakesTheFirstFloatGrid) {
    TempFile file(".vdb");
    auto velocity = makeGrid<openvdb::Vec3SGrid>("velocity", openvdb::Vec3s(0.0f));
    velocity->getAccessor().setValue(openvdb::Coord(0, 0, 0), openvdb::Vec3s(1.0f));
    auto mask = makeGrid<openvdb::BoolGrid>("mask", false);
    auto density = makeGrid<openvdb::DoubleGrid>("density", -1.0);
    density->getAccessor().setValue(openvdb::Coord(0, 0, 0), 0.25);
    density->getAccessor().setValue(openvdb::Coord(1, 1, 1), 4.0);
    writeGrids(file.path(), {velocity, mask, density});
    auto reader = openVdbVolume(file.path(), "");
    EXPECT_EQ(reader->info().dims, (Dims3{2, 2, 2}));
    const std::vector<float> v = readAll(*reader, {2});
    EXPECT_EQ(v, (std::vector<float>{0.25f, -1, -1, -1, -1, -1, -1, 4.0f}));
}

TEST(VdbReader, MissingGridNameListsTheGrids) {
    TempFile file(".vdb");
    writeDensityAndOther(file.path());
    const std::string message = ioErrorOf([&] { openVdbVolume(file.path(), "temperature"); });
    EXPECT_EQ(message.rfind(file.path() + ": ", 0), 0u) << message;
    EXPECT_NE(message.find("'temperature'"), std::string::npos) << message;
    EXPECT_NE(message.find("'density'"), std::string::npos) << message;
    EXPECT_NE(message.find("'other'"), std::string::npos) << message;
}

TEST(VdbReader, RejectsGridsOfOtherTypes) {
    TempFile file(".vdb");
    auto velocity = makeGrid<openvdb::Vec3SGrid>("velocity", openvdb::Vec3s(0.0f));
    velocity->getAccessor().setValue(openvdb::Coord(0, 0, 0), openvdb::Vec3s(1.0f));
    velocity->getAccessor().setValue(openvdb::Coord(1, 1, 1), openvdb::Vec3s(1.0f));
    auto count = makeGrid<openvdb::Int32Grid>("count", 0);
    writeGrids(file.path(), {velocity, count});
    const std::string vec3 = ioErrorOf([&] { openVdbVolume(file.path(), "velocity"); });
    EXPECT_EQ(vec3, file.path() +
                        ": grid 'velocity' holds vec3s values; only float and double grids can "
                        "be converted");
    const std::string int32 = ioErrorOf([&] { openVdbVolume(file.path(), "count"); });
    EXPECT_NE(int32.find("holds int32 values"), std::string::npos) << int32;
    const std::string none = ioErrorOf([&] { openVdbVolume(file.path(), ""); });
    EXPECT_NE(none.find("no float or double grid"), std::string::npos) << none;
    EXPECT_NE(none.find("'velocity' (vec3s)"), std::string::npos) << none;
}

TEST(VdbReader, RejectsEmptyAndFlatGrids) {
    TempFile file(".vdb");
    auto empty = makeGrid<openvdb::FloatGrid>("empty", 0.0f);
    auto flat = makeGrid<openvdb::FloatGrid>("flat", 0.0f);
    flat->getAccessor().setValue(openvdb::Coord(0, 0, 0), 1.0f);
    flat->getAccessor().setValue(openvdb::Coord(5, 5, 0), 1.0f);
    writeGrids(file.path(), {empty, flat});
    const std::string noVoxels = ioErrorOf([&] { openVdbVolume(file.path(), "empty"); });
    EXPECT_NE(noVoxels.find("no active voxels"), std::string::npos) << noVoxels;
    const std::string oneSlice = ioErrorOf([&] { openVdbVolume(file.path(), "flat"); });
    EXPECT_NE(oneSlice.find("6 x 6 x 1"), std::string::npos) << oneSlice;
}

TEST(VdbReader, RejectsFilesThatAreNotVdb) {
    TempFile file(".vdb");
    std::ofstream(file.path()) << "this is not a volume\n";
    const std::string message = ioErrorOf([&] { openVdbVolume(file.path(), ""); });
    EXPECT_EQ(message.rfind(file.path() + ": not an OpenVDB file", 0), 0u) << message;
    const std::string missing =
        ioErrorOf([&] { openVdbVolume(file.path() + ".missing", "density"); });
    EXPECT_EQ(missing.rfind(file.path() + ".missing: ", 0), 0u) << missing;
}

TEST(VdbReader, UnevenSlabsMatchAWholeRead) {
    TempFile file(".vdb");
    auto grid = makeGrid<openvdb::FloatGrid>("noise", -5.0f);
    auto acc = grid->getAccessor();
    // A sparse, irregular pattern across several leaf nodes (8^3), negative coordinates too.
    for (int z = -9; z < 14; ++z)
        for (int y = -3; y < 14; ++y)
            for (int x = -7; x < 13; ++x)
                if ((x * 7 + y * 13 + z * 29) % 5 == 0) acc.setValue({x, y, z}, float(x + y * z));
    writeGrids(file.path(), {grid});
    auto whole = openVdbVolume(file.path(), "noise");
    const Dims3 dims = whole->info().dims;
    EXPECT_EQ(dims[2], 23);
    const std::vector<float> expected = readAll(*whole, {dims[2]});
    auto slabs = openVdbVolume(file.path(), "noise");
    EXPECT_EQ(readAll(*slabs, {1, 4, 7, 2, 9}), expected);
    auto single = openVdbVolume(file.path(), "noise");
    EXPECT_EQ(readAll(*single, std::vector<int64_t>(23, 1)), expected);
    // And the values are the tree's, sample by sample.
    const openvdb::Coord lo = grid->evalActiveVoxelBoundingBox().min();
    size_t i = 0;
    for (int z = 0; z < dims[2]; ++z)
        for (int y = 0; y < dims[1]; ++y)
            for (int x = 0; x < dims[0]; ++x, ++i)
                ASSERT_EQ(expected[i], acc.getValue(lo.offsetBy(x, y, z))) << x << " " << y;
}

// The command line reads .vdb through the module beside the binary, and says so plainly when
// the module cannot be found.
TEST(VdbReader, ConvertFindsTheModuleOrSaysItIsMissing) {
    TempFile file(".vdb"), store(".vdiso");
    writeDensityAndOther(file.path());
    auto r = test::runVdiso("convert " + file.path() + " " + store.path() + " --grid density --quiet");
    EXPECT_EQ(r.exitCode, 0) << r.output;
    EXPECT_TRUE(std::filesystem::exists(store.path()));
    std::filesystem::remove(store.path());
    const std::string missing = "VDISO_MODULE_DIR=/nonexistent ";
    const std::string command = missing + VDISO_BINARY + " convert " + file.path() + " " +
                                store.path() + " 2>&1";
    FILE* pipe = ::popen(command.c_str(), "r");
    ASSERT_NE(pipe, nullptr);
    std::string output;
    char buf[512];
    while (size_t n = std::fread(buf, 1, sizeof buf, pipe)) output.append(buf, n);
    const int status = ::pclose(pipe);
    EXPECT_EQ(WEXITSTATUS(status), 1) << output;
    EXPECT_NE(output.find(file.path()), std::string::npos) << output;
    EXPECT_NE(output.find("libvdiso_vdb.so"), std::string::npos) << output;
    EXPECT_FALSE(std::filesystem::exists(store.path()));
}

TEST(VdbReader, ReadingPastTheLastSliceThrows) {
    TempFile file(".vdb");
    writeDensityAndOther(file.path());
    auto reader = openVdbVolume(file.path(), "density");
    std::vector<float> slab(size_t(reader->info().sliceSamples()) * 4);
    reader->read(slab.data(), 2);
    EXPECT_THROW(reader->read(slab.data(), 2), IoError);
}

}  // namespace
}  // namespace vdiso
