// vdiso-mpi under mpirun with 3 ranks (oversubscribed: the machine may have fewer cores): the
// mesh is the single process's byte for byte, the statistics show each rank's share, and a
// failure on one rank ends the job with one message naming it and no output. Built only when
// MPI was found (tests/CMakeLists.txt defines VDISO_MPI_COMMAND).
#ifdef VDISO_MPI_COMMAND

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <regex>
#include <string>
#include <vector>

#include "core/synth.h"
#include "io/brick_store.h"
#include "tests/test_util.h"

namespace vdiso {
namespace {

// CI runs as root, which OpenMPI refuses unless told twice. Under AddressSanitizer, leak
// detection is off for the ranks: OpenMPI leaves some 120 KB of its own allocations at
// MPI_Finalize, from components it has already unloaded (so no suppression can name them). The
// same extraction code is leak-checked in vdiso's own tests; ASan's other checks and UBSan stay.
test::CommandResult runMpi(int ranks, const std::string& args) {
    const std::string leaks = VDISO_UNDER_ASAN ? "ASAN_OPTIONS=\"${ASAN_OPTIONS:-}:detect_leaks=0\" " : "";
    return test::runCommand("OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 " + leaks +
                            std::string(VDISO_MPI_COMMAND) + " --oversubscribe -np " + std::to_string(ranks) +
                            " " + VDISO_MPI_BINARY + " " + args);
}

std::string text(const std::string& path) {
    const auto bytes = test::readFile(path);
    return std::string(bytes.begin(), bytes.end());
}

// The values of `"key": N` in `json`, in order (per_rank's entries after the totals).
std::vector<uint64_t> numbers(const std::string& json, const std::string& key) {
    std::vector<uint64_t> out;
    const std::regex re("\"" + key + "\": (-?[0-9]+)");
    for (auto it = std::sregex_iterator(json.begin(), json.end(), re); it != std::sregex_iterator(); ++it)
        out.push_back(uint64_t(std::stoll((*it)[1])));
    return out;
}

// The 3-rank mesh against the single process's, and the per-rank figures against the totals.
void expectSameAsSingleProcess(const std::string& synthArgs, double iso, const std::string& extra) {
    test::ScratchDir dir;
    const std::string store = dir.file("v.vdiso"), one = dir.file("one.ply"), three = dir.file("three.ply"),
                      stats = dir.file("s.json");
    ASSERT_EQ(test::runVdiso("synth " + store + " " + synthArgs + " --quiet").exitCode, 0);
    const std::string isoText = std::to_string(iso);
    auto r = test::runVdiso("extract " + store + " --iso " + isoText + " --quiet -o " + one);
    ASSERT_EQ(r.exitCode, 0) << r.output;
    r = runMpi(3, "extract " + store + " --iso " + isoText + " --method octree --quiet -o " + three + " --stats " +
                      stats + extra);
    ASSERT_EQ(r.exitCode, 0) << r.output;
    const auto a = test::readFile(one), b = test::readFile(three);
    ASSERT_GT(a.size(), 512u);
    EXPECT_EQ(a.size(), b.size());
    EXPECT_TRUE(a == b) << "the 3-rank PLY differs from the single process's";

    const std::string json = text(stats);
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
    const std::vector<uint64_t> first = numbers(text(stats), "first_brick");
    ASSERT_EQ(first.size(), 3u);
    uint64_t offset = 0;
    {
        const BrickStoreReader reader(store);
        const BrickEntry& e = reader.index().at(size_t(first[1]));
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
    r = runMpi(2, "convert a b");
    EXPECT_EQ(r.exitCode, 2);
    EXPECT_NE(r.output.find("convert is not yet under MPI"), std::string::npos) << r.output;
    r = runMpi(2, "extract " + store + " --iso 600.5 --method sage");
    EXPECT_EQ(r.exitCode, 2);
    EXPECT_NE(r.output.find("not yet under MPI"), std::string::npos) << r.output;
    r = runMpi(2, "extract " + store + " --iso 600.5 --png x.png");
    EXPECT_EQ(r.exitCode, 2);
    EXPECT_NE(r.output.find("--png is not yet under MPI"), std::string::npos) << r.output;
    r = runMpi(2, "extract " + store + " --iso 600.5 -o " + dir.file("h.obj"));
    EXPECT_EQ(r.exitCode, 2);
    EXPECT_NE(r.output.find("only .ply meshes"), std::string::npos) << r.output;
    EXPECT_FALSE(std::filesystem::exists(dir.file("h.obj")));
    test::writeFile(mesh, std::string("keep"));
    r = runMpi(2, "extract " + store + " --iso 600.5 -o " + mesh);
    EXPECT_EQ(r.exitCode, 2);
    EXPECT_NE(r.output.find("already exists"), std::string::npos) << r.output;
    EXPECT_EQ(text(mesh), "keep");
    r = runMpi(2, "extract " + store + " --iso 600.5 --quiet --force -o " + mesh);
    EXPECT_EQ(r.exitCode, 0) << r.output;
    EXPECT_EQ(text(mesh).substr(0, 4), "ply\n");
}

}  // namespace
}  // namespace vdiso

#endif  // VDISO_MPI_COMMAND
