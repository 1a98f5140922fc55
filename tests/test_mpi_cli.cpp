// vdiso-mpi under mpirun with 3 ranks (oversubscribed: the machine may have fewer cores): the
// mesh (extract) and the store (convert) are the single process's, the statistics show each
// rank's share, and a failure on one rank ends the job with one message naming it and no
// output. Built only when MPI was found (tests/CMakeLists.txt defines VDISO_MPI_COMMAND).
#ifdef VDISO_MPI_COMMAND

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "core/synth/synth.h"
#include "io/store/brick_store.h"
#include "io/render/image_compare.h"
#include "io/render/png_image.h"
#include "tests/mpi_test_util.h"
#include "tests/test_util.h"

namespace vdiso {
namespace {

using test::numbers;
using test::readText;
using test::runMpi;

// The 3-rank mesh against the single process's, and the per-rank figures against the totals.
void expectSameAsSingleProcess(const std::string& synthArgs, double iso, const std::string& extra) {
    test::ScratchDir dir;
    const std::string store = dir.file("v.vdiso"), one = dir.file("one.ply"), three = dir.file("three.ply"),
                      stats = dir.file("s.json");
    ASSERT_EQ(test::runVdiso("synth " + store + " " + synthArgs + " --quiet").exitCode, 0);
    const std::string isoText = std::to_string(iso);
    const std::string oneStats = dir.file("one.json");
    auto r = test::runVdiso("extract " + store + " --iso " + isoText + " --method octree --quiet -o " + one +
                            " --stats " + oneStats);
    ASSERT_EQ(r.exitCode, 0) << r.output;
    r = runMpi(3, "extract " + store + " --iso " + isoText + " --method octree --quiet -o " + three + " --stats " +
                      stats + extra);
    ASSERT_EQ(r.exitCode, 0) << r.output;
    const auto a = test::readFile(one), b = test::readFile(three);
    ASSERT_GT(a.size(), 512u);
    EXPECT_EQ(a.size(), b.size());
    EXPECT_TRUE(a == b) << "the 3-rank PLY differs from the single process's";
    // STL: each rank's own triangles, no welding, at the offsets of the ranks before it.
    const std::string oneStl = dir.file("one.stl"), threeStl = dir.file("three.stl");
    r = test::runVdiso("extract " + store + " --iso " + isoText + " --quiet -o " + oneStl);
    ASSERT_EQ(r.exitCode, 0) << r.output;
    r = runMpi(3, "extract " + store + " --iso " + isoText + " --quiet -o " + threeStl + extra);
    ASSERT_EQ(r.exitCode, 0) << r.output;
    const auto c = test::readFile(oneStl), d = test::readFile(threeStl);
    ASSERT_GT(c.size(), 84u);
    EXPECT_TRUE(c == d) << "the 3-rank STL differs from the single process's";

    const std::string json = readText(stats);
    EXPECT_NE(json.find("\"ranks\": 3"), std::string::npos) << json;
    const std::vector<uint64_t> triangles = numbers(json, "triangles"), bricks = numbers(json, "bricks"),
                                owned = numbers(json, "vertices_owned"), vertices = numbers(json, "vertices"),
                                active = numbers(json, "bricks_active"), loaded = numbers(json, "bricks_loaded");
    ASSERT_EQ(triangles.size(), 4u) << json;  // the total, then one per rank
    ASSERT_EQ(bricks.size(), 3u) << json;
    ASSERT_EQ(owned.size(), 3u) << json;
    ASSERT_EQ(loaded.size(), 4u) << json;
    for (int k = 0; k < 3; ++k) {
        EXPECT_GT(bricks[size_t(k)], 0u) << "rank " << k << ": " << json;
        EXPECT_GT(triangles[size_t(k) + 1], 0u) << "rank " << k << ": " << json;
    }
    EXPECT_EQ(triangles[1] + triangles[2] + triangles[3], triangles[0]);
    EXPECT_EQ(owned[0] + owned[1] + owned[2], vertices.at(0));
    EXPECT_EQ(bricks[0] + bricks[1] + bricks[2], active.at(0));
    // Each rank reads its own bricks only: together, each active brick once.
    EXPECT_EQ(loaded[1] + loaded[2] + loaded[3], active.at(0));
    // The header and the traversal's counts are the single process's, by the same writer.
    const nlohmann::json ranks = nlohmann::json::parse(json), single = nlohmann::json::parse(readText(oneStats));
    for (const char* key : {"file", "method", "iso", "metacell", "level", "levels", "mesh_space", "triangles",
                            "points", "vertices", "bricks_active", "meta_cells_active", "cells_active"}) {
        ASSERT_TRUE(single.contains(key) && ranks.contains(key)) << key << "\n" << json << "\n" << single;
        EXPECT_EQ(ranks[key], single[key]) << key;
    }
}

TEST(MpiExtract, HeadIsByteIdenticalToOneProcess) {
    expectSameAsSingleProcess("--kind head --size 64 --brick 8", kHeadSkinIso, "");
}

TEST(MpiExtract, TurbulenceWithThreadsIsByteIdenticalToOneProcess) {
    // Threads inside each rank: chunks within the rank, ranks across; still one numbering.
    expectSameAsSingleProcess("--kind turbulence --size 48 --brick 8", turbulenceIso(ScalarType::U16),
                              " --threads 2");
}

TEST(MpiExtract, CorruptBrickOnOneRankFailsTheJobWithoutOutput) {
    test::ScratchDir dir;
    const std::string store = dir.file("h.vdiso"), mesh = dir.file("h.ply"), stats = dir.file("s.json");
    ASSERT_EQ(test::runVdiso("synth " + store + " --kind head --size 48 --brick 8 --quiet").exitCode, 0);
    const std::string iso = std::to_string(kHeadSkinIso);
    auto r = runMpi(3, "extract " + store + " --iso " + iso + " --quiet --stats " + stats);
    ASSERT_EQ(r.exitCode, 0) << r.output;
    // A brick in rank 1's part: its stored bytes flipped, so its checksum fails there only.
    const std::vector<uint64_t> first = numbers(readText(stats), "first_brick");
    ASSERT_EQ(first.size(), 3u);
    uint64_t offset = 0;
    {
        const BrickStoreReader reader(store);
        ASSERT_LT(first[1], reader.index().size());
        const BrickEntry& e = reader.index()[size_t(first[1])];
        offset = e.offset + e.storedBytes / 2;
    }
    {
        std::fstream f(store, std::ios::in | std::ios::out | std::ios::binary);
        f.seekg(std::streamoff(offset));
        const char c = char(f.get());
        f.seekp(std::streamoff(offset));
        f.put(char(~c));
    }
    r = runMpi(3, "extract " + store + " --iso " + iso + " -o " + mesh);
    EXPECT_EQ(r.exitCode, 1) << r.output;
    EXPECT_NE(r.output.find("vdiso-mpi extract: rank 1: "), std::string::npos) << r.output;
    EXPECT_NE(r.output.find(store), std::string::npos) << r.output;
    // One message, from rank 0, and nothing left beside the store.
    EXPECT_EQ(r.output.find("vdiso-mpi extract: "), r.output.rfind("vdiso-mpi extract: ")) << r.output;
    EXPECT_FALSE(std::filesystem::exists(mesh));
    for (const auto& entry : std::filesystem::directory_iterator(dir.path()))
        EXPECT_EQ(entry.path().string().find(".partial"), std::string::npos) << entry.path();
}

TEST(MpiExtract, MissingStoreAndRefusals) {
    test::ScratchDir dir;
    const std::string store = dir.file("h.vdiso"), mesh = dir.file("h.ply");
    auto r = runMpi(3, "extract " + dir.file("missing.vdiso") + " --iso 1 -o " + mesh);
    EXPECT_EQ(r.exitCode, 1) << r.output;
    EXPECT_NE(r.output.find("vdiso-mpi extract: rank 0: " + dir.file("missing.vdiso")), std::string::npos)
        << r.output;
    EXPECT_FALSE(std::filesystem::exists(mesh));
    // Not yet under MPI: other commands, methods and formats; existing output without --force.
    ASSERT_EQ(test::runVdiso("synth " + store + " --kind head --size 24 --brick 8 --quiet").exitCode, 0);
    r = runMpi(2, "info a");
    EXPECT_EQ(r.exitCode, 2);
    EXPECT_NE(r.output.find("info is not yet under MPI"), std::string::npos) << r.output;
    r = runMpi(2, "extract " + store + " --iso 600.5 --method noise");
    EXPECT_EQ(r.exitCode, 2);
    EXPECT_NE(r.output.find("--method noise is not under MPI"), std::string::npos) << r.output;
    r = runMpi(2, "extract " + store + " --iso 600.5 --png x.png");
    EXPECT_EQ(r.exitCode, 2);
    EXPECT_NE(r.output.find("--png with --method octree is not under MPI"), std::string::npos) << r.output;
    r = runMpi(2, "extract " + store + " --iso 600.5 -o " + dir.file("h.obj"));
    EXPECT_EQ(r.exitCode, 2);
    EXPECT_NE(r.output.find("writes .ply and .stl meshes under MPI"), std::string::npos) << r.output;
    EXPECT_FALSE(std::filesystem::exists(dir.file("h.obj")));
    test::writeFile(mesh, std::string("keep"));
    r = runMpi(2, "extract " + store + " --iso 600.5 -o " + mesh);
    EXPECT_EQ(r.exitCode, 2);
    EXPECT_NE(r.output.find("already exists"), std::string::npos) << r.output;
    EXPECT_EQ(readText(mesh), "keep");
    r = runMpi(2, "extract " + store + " --iso 600.5 --quiet --force -o " + mesh);
    EXPECT_EQ(r.exitCode, 0) << r.output;
    EXPECT_EQ(readText(mesh).substr(0, 4), "ply\n");
}

// The picture of a view-dependent extraction shared by 3 ranks, against the single process's.
double pictureAgreement(const std::string& reference, const std::string& other) {
    return compareImages(readPng(reference), readPng(other)).agreement();
}

TEST(MpiView, SagePictureIsTheSingleProcessOnesByImageAndByObject) {
    test::ScratchDir dir;
    const std::string store = dir.file("h.vdiso"), one = dir.file("one.png");
    ASSERT_EQ(test::runVdiso("synth " + store + " --kind head --size 96 --brick 8 --quiet").exitCode, 0);
    const std::string common = "extract " + store + " --iso " + std::to_string(kHeadSkinIso) +
                               " --method sage --size 400x400 --prefetch 0 --quiet ";
    auto r = test::runVdiso(common + "--threads 1 --png " + one);
    ASSERT_EQ(r.exitCode, 0) << r.output;
    uint64_t objectLoaded = 0;
    for (const std::string partition : {"image", "object"}) {
        const std::string png = dir.file(partition + ".png"), mesh = dir.file(partition + ".obj"),
                          stats = dir.file(partition + ".json");
        r = runMpi(3, common + "--partition " + partition + " --png " + png + " -o " + mesh + " --stats " + stats);
        ASSERT_EQ(r.exitCode, 0) << r.output;
        EXPECT_GE(pictureAgreement(one, png), 0.995) << partition;
        EXPECT_GT(std::filesystem::file_size(mesh), 1000u) << partition;  // any mesh format, from rank 0
        const std::string json = readText(stats);
        EXPECT_NE(json.find("\"ranks\": 3"), std::string::npos) << json;
        EXPECT_NE(json.find("\"partition\": \"" + partition + "\""), std::string::npos) << json;
        const std::vector<uint64_t> triangles = numbers(json, "triangles"), loaded = numbers(json, "bricks_loaded");
        ASSERT_EQ(triangles.size(), 4u) << json;  // the total, then one per rank
        ASSERT_EQ(loaded.size(), 4u) << json;
        // Every rank did a real share: it read bricks and made triangles, and the shares add up.
        for (size_t k = 1; k <= 3; ++k) {
            EXPECT_GT(triangles[k], triangles[0] / 10) << partition << " rank " << k - 1 << ": " << json;
            EXPECT_GT(loaded[k], 0u) << partition << " rank " << k - 1 << ": " << json;
        }
        EXPECT_EQ(triangles[1] + triangles[2] + triangles[3], triangles[0]);
        EXPECT_EQ(loaded[1] + loaded[2] + loaded[3], loaded[0]);
        // The parts tile the image's columns, or the volume's layers.
        const std::string unit = partition == "image" ? "column" : "layer";
        const std::vector<uint64_t> first = numbers(json, "first_" + unit), end = numbers(json, "end_" + unit);
        ASSERT_EQ(first.size(), 3u) << json;
        ASSERT_EQ(end.size(), 3u) << json;
        EXPECT_EQ(first[0], 0u);
        EXPECT_EQ(first[1], end[0]);
        EXPECT_EQ(first[2], end[1]);
        EXPECT_EQ(end[2], partition == "image" ? 400u : 12u);  // 96 samples in bricks of 8: 12 layers
        if (partition == "object") {
            EXPECT_GT(numbers(json, "coverage_rounds").at(0), 1u) << json;
            for (uint64_t culled : numbers(json, "culled_region")) EXPECT_GT(culled, 0u) << json;
            objectLoaded = loaded[0];
        }
    }
    // The coverage trades are what spares the slabs behind the reads of what the front hides:
    // with one trade only (before any brick), they read much more.
    const std::string stats = dir.file("lone.json");
    r = runMpi(3, common + "--partition object --exchange-bricks 1000000 --stats " + stats);
    ASSERT_EQ(r.exitCode, 0) << r.output;
    const uint64_t lone = numbers(readText(stats), "bricks_loaded").at(0);
    EXPECT_LT(double(objectLoaded), 0.85 * double(lone)) << objectLoaded << " bricks with trades, " << lone
                                                        << " without";
}

// The eye inside the volume, in the middle slab a cell and a half past its cut with the first,
// with a view wide enough to see slabs on both sides of it: both coverage scans run (toward
// each side of the eye's slab). (Nothing behind the near plane is made: from the slab's middle,
// the first slab's surface lay out of view and its rank made only such triangles.)
TEST(MpiView, ObjectPartitionWithTheEyeInsideTheVolume) {
    test::ScratchDir dir;
    const std::string store = dir.file("h.vdiso"), one = dir.file("one.png"), three = dir.file("three.png"),
                      cam = dir.file("cam.json"), stats = dir.file("s.json");
    ASSERT_EQ(test::runVdiso("synth " + store + " --kind head --size 96 --brick 8 --quiet").exitCode, 0);
    test::writeFile(cam, std::string(R"({"eye": [41.5, 47.5, 47.5], "target": [51.5, 56.5, 49.5], "up": [0, 0, 1],)"
                                     R"( "fov": 110, "width": 400, "height": 400})"));
    const std::string common = "extract " + store + " --iso " + std::to_string(kHeadSkinIso) +
                               " --method sage --lod-error 0 --quiet --camera " + cam + " ";
    auto r = test::runVdiso(common + "--threads 1 --png " + one);
    ASSERT_EQ(r.exitCode, 0) << r.output;
    r = runMpi(3, common + "--partition object --png " + three + " --stats " + stats);
    ASSERT_EQ(r.exitCode, 0) << r.output;
    const std::string json = readText(stats);
    EXPECT_NE(json.find("\"slab_axis\": \"x\""), std::string::npos) << json;
    EXPECT_NE(json.find("\"eye_slab\": 1,"), std::string::npos) << json;
    const std::vector<uint64_t> triangles = numbers(json, "triangles");  // the total, then each rank's
    ASSERT_EQ(triangles.size(), 4u) << json;
    for (size_t k = 1; k < 4; ++k) EXPECT_GT(triangles[k], 0u) << "rank " << k - 1 << ": " << json;
    const ImageAgreement a = compareImages(readPng(one), readPng(three));
    EXPECT_GT(a.referenceCovered, 10000u);
    EXPECT_GE(a.agreement(), 0.995) << a.missing << " missing";
}

TEST(MpiView, CorruptBrickInOneSlabFailsTheJobNamingItsRank) {
    test::ScratchDir dir;
    const std::string store = dir.file("h.vdiso"), png = dir.file("h.png"), stats = dir.file("s.json");
    ASSERT_EQ(test::runVdiso("synth " + store + " --kind head --size 64 --brick 8 --quiet").exitCode, 0);
    const std::string common =
        "extract " + store + " --iso " + std::to_string(kHeadSkinIso) + " --method sage --partition object ";
    auto r = runMpi(3, common + "--quiet --stats " + stats);
    ASSERT_EQ(r.exitCode, 0) << r.output;
    const std::string json = readText(stats);
    const std::vector<uint64_t> first = numbers(json, "first_layer"), end = numbers(json, "end_layer");
    ASSERT_EQ(first.size(), 3u) << json;
    const std::smatch axis = [&] {
        std::smatch m;
        std::regex_search(json, m, std::regex("\"slab_axis\": \"([xyz])\""));
        return m;
    }();
    ASSERT_FALSE(axis.empty()) << json;
    const int a = axis[1].str()[0] - 'x';
    // Every level-0 brick of rank 1's slab flipped in the middle: the first it reads fails its
    // checksum. Ranks 0 and 2 are in their coverage rounds meanwhile, and must end too.
    {
        const BrickStoreReader reader(store);
        const BrickLayout& layout = reader.layout();
        std::fstream f(store, std::ios::in | std::ios::out | std::ios::binary);
        for (int64_t id = 0; id < layout.brickCount(); ++id) {
            const int64_t c = layout.brickCoord(id)[a];
            if (c < int64_t(first[1]) || c >= int64_t(end[1])) continue;
            const BrickEntry& e = reader.index()[size_t(id)];
            const uint64_t offset = e.offset + e.storedBytes / 2;
            f.seekg(std::streamoff(offset));
            const char byte = char(f.get());
            f.seekp(std::streamoff(offset));
            f.put(char(~byte));
        }
    }
    r = runMpi(3, common + "--png " + png);
    EXPECT_EQ(r.exitCode, 1) << r.output;
    EXPECT_NE(r.output.find("vdiso-mpi extract: rank 1: "), std::string::npos) << r.output;
    EXPECT_NE(r.output.find(store), std::string::npos) << r.output;
    EXPECT_EQ(r.output.find("vdiso-mpi extract: "), r.output.rfind("vdiso-mpi extract: ")) << r.output;
    EXPECT_FALSE(std::filesystem::exists(png));
}

TEST(MpiView, Refusals) {
    test::ScratchDir dir;
    const std::string store = dir.file("h.vdiso");
    ASSERT_EQ(test::runVdiso("synth " + store + " --kind head --size 24 --brick 8 --quiet").exitCode, 0);
    const std::string common = "extract " + store + " --iso 600.5 ";
    const std::pair<std::string, std::string> cases[] = {
        {"--partition object", "--partition applies to --method sage or wise"},
        {"--method sage --partition depth", "--partition expects image or object"},
        {"--method sage --partition object --lod-error 1", "full resolution (--lod-error 0)"},
        {"--method sage --partition object --threads 2", "one thread per rank"},
        {"--method sage --path orbit:4 --png f%d.png", "--path is not under MPI"},
        {"--method sage --oracle", "--oracle is not under MPI"},
        {"--method sage --exchange-bricks 0", "--exchange-bricks"},
        {"--method sage --exchange-bricks 8", "--exchange-bricks applies to --partition object"},
    };
    for (const auto& [options, message] : cases) {
        const auto r = runMpi(2, common + options);
        EXPECT_EQ(r.exitCode, 2) << options << ": " << r.output;
        EXPECT_NE(r.output.find(message), std::string::npos) << options << ": " << r.output;
    }
}

}  // namespace
}  // namespace vdiso

#endif  // VDISO_MPI_COMMAND
