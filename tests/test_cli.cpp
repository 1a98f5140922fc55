// The command line as a user meets it: exit codes, one clear message naming the file, and no
// output left behind (or overwritten) when anything goes wrong.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstring>
#include <filesystem>
#include <string>
#include <thread>

#include <zlib.h>

#include "io/store/brick_store.h"
#include "tests/mesh_test_readers.h"
#include "tests/test_util.h"

namespace vdiso {
namespace {

using test::runVdiso;
using test::ScratchDir;

bool contains(const std::string& s, const std::string& part) { return s.find(part) != std::string::npos; }

TEST(Cli, ConvertRawAndDescribeIt) {
    ScratchDir dir;
    const std::string raw = dir.file("v.raw"), out = dir.file("v.vdiso");
    std::vector<uint16_t> samples(size_t(20 * 18 * 17));
    for (size_t i = 0; i < samples.size(); ++i) samples[i] = uint16_t(i % 1000);
    test::writeFile(raw, samples.data(), samples.size() * 2);
    auto r = runVdiso("convert " + raw + " " + out + " --dims 20,18,17 --type u16 --brick 8 --spacing 0.5");
    ASSERT_EQ(r.exitCode, 0) << r.output;
    r = runVdiso("info " + out);
    ASSERT_EQ(r.exitCode, 0) << r.output;
    EXPECT_TRUE(contains(r.output, "20 x 18 x 17  u16")) << r.output;
    EXPECT_TRUE(contains(r.output, "0.5 x 0.5 x 0.5")) << r.output;
    EXPECT_TRUE(contains(r.output, "0 .. 999")) << r.output;

    // --iso counts exactly level 0's bricks whose range holds the isovalue.
    const BrickStoreReader store(out);
    size_t active = 0;
    for (int64_t id = 0; id < store.layout().brickCount(); ++id) {
        const BrickEntry& e = store.index()[size_t(id)];
        active += (e.minValue <= 500.5 && 500.5 < e.maxValue);
    }
    r = runVdiso("info " + out + " --iso 500.5 --json");
    ASSERT_EQ(r.exitCode, 0) << r.output;
    EXPECT_TRUE(contains(r.output, "\"active_bricks\": " + std::to_string(active))) << r.output;
    EXPECT_TRUE(contains(r.output, "\"dims\": [20, 18, 17]")) << r.output;
}

TEST(Cli, ShortRawInputFailsAndLeavesNothing) {
    ScratchDir dir;
    const std::string raw = dir.file("v.raw"), out = dir.file("v.vdiso");
    test::writeFile(raw, std::string(999, 'x'));
    auto r = runVdiso("convert " + raw + " " + out + " --dims 10,10,10 --type u8");
    EXPECT_EQ(r.exitCode, 1);
    EXPECT_TRUE(contains(r.output, raw + ": file is 1 bytes shorter")) << r.output;
    EXPECT_FALSE(std::filesystem::exists(out));
    test::writeFile(raw, std::string(1001, 'x'));
    r = runVdiso("convert " + raw + " " + out + " --dims 10,10,10 --type u8");
    EXPECT_EQ(r.exitCode, 1);
    EXPECT_TRUE(contains(r.output, "1 bytes longer")) << r.output;
    EXPECT_FALSE(std::filesystem::exists(out));
}

TEST(Cli, UnknownTypeIsAUsageError) {
    ScratchDir dir;
    const std::string raw = dir.file("v.raw");
    test::writeFile(raw, std::string(8, 'x'));
    auto r = runVdiso("convert " + raw + " " + dir.file("o.vdiso") + " --dims 2,2,2 --type u12");
    EXPECT_EQ(r.exitCode, 2);
    EXPECT_TRUE(contains(r.output, "unknown type 'u12'")) << r.output;
    EXPECT_TRUE(contains(r.output, "i8, i32, u32 or f64")) << r.output;  // every type it takes
}

TEST(Cli, ExistingOutputIsNeverTouched) {
    ScratchDir dir;
    const std::string raw = dir.file("v.raw"), out = dir.file("v.vdiso");
    test::writeFile(raw, std::string(8, 'x'));
    test::writeFile(out, "keep me");
    auto r = runVdiso("convert " + raw + " " + out + " --dims 2,2,2 --type u8");
    EXPECT_EQ(r.exitCode, 1);
    EXPECT_TRUE(contains(r.output, out + ": already exists")) << r.output;
    EXPECT_EQ(test::readFile(out).size(), 7u);
    // A failing conversion with --force does not touch it either.
    r = runVdiso("convert " + raw + " " + out + " --dims 3,3,3 --type u8 --force");
    EXPECT_EQ(r.exitCode, 1);
    EXPECT_EQ(test::readFile(out).size(), 7u);
    // A succeeding one with --force replaces it.
    r = runVdiso("convert " + raw + " " + out + " --dims 2,2,2 --type u8 --force --quiet");
    EXPECT_EQ(r.exitCode, 0) << r.output;
    EXPECT_GT(test::readFile(out).size(), 4096u);
}

TEST(Cli, UnwritableOutputIsReported) {
    ScratchDir dir;
    const std::string raw = dir.file("v.raw");
    test::writeFile(raw, std::string(8, 'x'));
    auto r = runVdiso("convert " + raw + " /nonexistent-dir/o.vdiso --dims 2,2,2 --type u8");
    EXPECT_EQ(r.exitCode, 1);
    EXPECT_TRUE(contains(r.output, "/nonexistent-dir/o.vdiso: cannot write")) << r.output;
}

TEST(Cli, CorruptGzipFailsAndLeavesNothing) {
    ScratchDir dir;
    // A valid NIfTI header followed by a gzip stream whose middle is damaged.
    const std::string nii = dir.file("v.nii"), gz = dir.file("v.nii.gz"), out = dir.file("v.vdiso");
    std::vector<unsigned char> header(352, 0);
    auto put16 = [&](size_t at, int16_t v) { std::memcpy(&header[at], &v, 2); };
    auto put32 = [&](size_t at, int32_t v) { std::memcpy(&header[at], &v, 4); };
    auto putF = [&](size_t at, float v) { std::memcpy(&header[at], &v, 4); };
    put32(0, 348);
    put16(40, 3);
    put16(42, 64);
    put16(44, 64);
    put16(46, 64);
    put16(70, 2);  // uint8
    put16(72, 8);
    putF(76, 1.0f);
    putF(80, 1.0f);
    putF(84, 1.0f);
    putF(88, 1.0f);
    putF(108, 352.0f);
    std::memcpy(&header[344], "n+1\0", 4);
    std::vector<unsigned char> data(header);
    for (int i = 0; i < 64 * 64 * 64; ++i) data.push_back(uint8_t((i * 7919) >> 5));
    gzFile f = gzopen(gz.c_str(), "wb");
    gzwrite(f, data.data(), unsigned(data.size()));
    gzclose(f);
    auto bytes = test::readFile(gz);
    for (size_t i = bytes.size() / 2; i < bytes.size() / 2 + 64; ++i) bytes[i] ^= 0x5a;
    test::writeFile(gz, bytes.data(), bytes.size());
    auto r = runVdiso("convert " + gz + " " + out);
    EXPECT_EQ(r.exitCode, 1) << r.output;
    EXPECT_TRUE(contains(r.output, gz)) << r.output;
    EXPECT_TRUE(contains(r.output, "gzip")) << r.output;
    EXPECT_FALSE(std::filesystem::exists(out));
    EXPECT_FALSE(std::filesystem::exists(nii));
}

TEST(Cli, InfoRefusesNonStores) {
    ScratchDir dir;
    const std::string f = dir.file("x.vdiso");
    test::writeFile(f, std::string(5000, 'z'));
    auto r = runVdiso("info " + f);
    EXPECT_EQ(r.exitCode, 1);
    EXPECT_TRUE(contains(r.output, f + ": not a vdiso brick store")) << r.output;
    r = runVdiso("info " + dir.file("missing.vdiso"));
    EXPECT_EQ(r.exitCode, 1);
    EXPECT_TRUE(contains(r.output, "missing.vdiso: cannot open")) << r.output;
}

TEST(Cli, SynthHeadStoreAndRawAgree) {
    ScratchDir dir;
    const std::string store = dir.file("h.vdiso"), raw = dir.file("h.raw"), conv = dir.file("c.vdiso");
    ASSERT_EQ(runVdiso("synth " + store + " --kind head --size 40,36,32 --quiet").exitCode, 0);
    ASSERT_EQ(runVdiso("synth " + raw + " --kind head --size 40,36,32 --quiet").exitCode, 0);
    EXPECT_EQ(test::readFile(raw).size(), size_t(40 * 36 * 32 * 2));
    ASSERT_EQ(runVdiso("convert " + raw + " " + conv + " --dims 40,36,32 --type u16 --quiet").exitCode, 0);
    // Same samples, same bricks: the two stores are byte-identical.
    EXPECT_EQ(test::readFile(store), test::readFile(conv));
    const BrickStoreReader s(store);
    EXPECT_LT(s.header().valueMin, 600.5);
    EXPECT_GT(s.header().valueMax, 1224.5);
}

TEST(Cli, HelpAndUsage) {
    for (const char* cmd : {"convert", "synth", "info"}) {
        auto r = runVdiso(std::string(cmd) + " --help");
        EXPECT_EQ(r.exitCode, 0) << cmd;
        EXPECT_TRUE(contains(r.output, std::string("usage: vdiso ") + cmd)) << r.output;
    }
    EXPECT_EQ(runVdiso("frobnicate").exitCode, 2);
    EXPECT_EQ(runVdiso("convert a.raw").exitCode, 2);
    EXPECT_EQ(runVdiso("synth x.raw --kind head --size 8 --type u8").exitCode, 2);
}


TEST(CliExtract, WritesMeshPictureAndStats) {
    test::ScratchDir dir;
    const std::string store = dir.file("h.vdiso"), ply = dir.file("h.ply"), obj = dir.file("h.obj"),
                      png = dir.file("h.png"), stats = dir.file("s.json");
    ASSERT_EQ(test::runVdiso("synth " + store + " --kind head --size 40 --brick 8 --quiet").exitCode, 0);
    auto r = test::runVdiso("extract " + store + " --iso 600.5 -o " + ply + " --png " + png +
                            " --view distant --size 64x48 --stats " + stats);
    ASSERT_EQ(r.exitCode, 0) << r.output;
    const auto json = test::readFile(stats);
    const std::string text(json.begin(), json.end());
    for (const char* key : {"\"method\": \"octree\"", "\"triangles\": ", "\"vertices\": ",
                            "\"extract_s\": ", "\"io_s\": ", "\"bricks_loaded\": ",
                            "\"bytes_read\": ", "\"peak_rss_mb\": ", "\"draw_s\": "})
        EXPECT_NE(text.find(key), std::string::npos) << key << " in " << text;
    const auto plyBytes = test::readFile(ply);
    EXPECT_EQ(std::string(plyBytes.begin(), plyBytes.begin() + 3), "ply");
    EXPECT_GT(test::readFile(png).size(), 100u);
    // Existing outputs are refused before any work; OBJ output works too.
    r = test::runVdiso("extract " + store + " --iso 600.5 -o " + ply);
    EXPECT_EQ(r.exitCode, 2);
    EXPECT_NE(r.output.find("already exists"), std::string::npos) << r.output;
    r = test::runVdiso("extract " + store + " --iso 600.5 --method noise -o " + obj + " --quiet");
    EXPECT_EQ(r.exitCode, 0) << r.output;
    EXPECT_EQ(test::readFile(obj)[0], '#');
}

// SAGE's statistics split the time of visible meta-cells between the visibility work (sampled:
// cell tests, projection, coverage; box tests beside) and the kernel, in seconds and per kept
// triangle: every timer measured (none left at zero by a timer not wired), on every SIMD path
// (core/simd.h), with the same triangles on each. The kernel is no timer of its own but the
// scan's sampled time less the parts' sampled times, clamped at zero: on an extraction this
// small the samples can make it zero (it did under the sanitizers at meta-cells of 8, and in a
// loaded Release run at 4), so the scan's timer is what must be wired and the kernel at least 0.
TEST(CliExtract, SageStatsSplitTheVisibilityWorkFromTheKernel) {
    test::ScratchDir dir;
    const std::string store = dir.file("h.vdiso");
    ASSERT_EQ(test::runVdiso("synth " + store + " --kind head --size 96 --brick 16 --quiet").exitCode, 0);
    uint64_t triangles[2] = {0, 0};
    for (int path = 0; path < 2; ++path) {
        const auto r = test::runCommand(std::string(path == 0 ? "VDISO_SIMD=baseline " : "") + VDISO_BINARY +
                                        " extract " + store +
                                        " --iso 600.5 --method sage --size 512x512 --metacell 4 --threads 1 --stats - --quiet");
        ASSERT_EQ(r.exitCode, 0) << r.output;
        const nlohmann::json stats = nlohmann::json::parse(r.output);
        triangles[path] = stats["triangles"];
        for (const char* key : {"cell_test_s", "projection_s", "coverage_s", "box_test_s", "kernel_s",
                                "visibility_ns_per_triangle", "kernel_ns_per_triangle"})
            ASSERT_TRUE(stats.contains(key)) << key << " in " << r.output;
        EXPECT_GT(double(stats["coverage_s"]), 0.0) << r.output;
        EXPECT_GT(double(stats["scan_s"]), 0.0) << r.output;
        EXPECT_GE(double(stats["kernel_s"]), 0.0) << r.output;
        EXPECT_GE(double(stats["kernel_ns_per_triangle"]), 0.0) << r.output;
        EXPECT_GT(double(stats["visibility_ns_per_triangle"]), 0.0) << r.output;
        EXPECT_GT(double(stats["cell_test_s"]), 0.0) << r.output;
        EXPECT_GT(double(stats["projection_s"]), 0.0) << r.output;
        EXPECT_GT(double(stats["box_test_s"]), 0.0) << r.output;
    }
    EXPECT_GT(triangles[0], 1000u);
    EXPECT_EQ(triangles[0], triangles[1]);
}

// Every mesh format from a streamed extraction (and a held one, with a picture) has the PLY's
// vertices and triangles; --mesh-compress is for .glb only; an unknown extension is refused
// naming it; an existing output is kept without --force.
TEST(CliExtract, WritesEveryMeshFormat) {
    test::ScratchDir dir;
    const std::string store = dir.file("h.vdiso");
    ASSERT_EQ(runVdiso("synth " + store + " --kind head --size 40 --brick 8 --quiet").exitCode, 0);
    const std::string extract = "extract " + store + " --iso 600.5 --quiet -o ";
    ASSERT_EQ(runVdiso(extract + dir.file("h.ply")).exitCode, 0);
    const TriangleMesh ply = test::readPly(dir.file("h.ply"));
    ASSERT_GT(ply.triangleCount(), 1000u);
    for (const char* name : {"h.stl", "h.glb", "h.vtp"}) {
        const auto r = runVdiso(extract + dir.file(name));
        EXPECT_EQ(r.exitCode, 0) << name << ": " << r.output;
    }
    for (const char* options : {" --mesh-compress", " --mesh-compress --png " /* held mesh */}) {
        const bool png = std::strstr(options, "png") != nullptr;
        const std::string name = png ? "held.glb" : "packed.glb";
        const auto r = runVdiso(extract + dir.file(name) + options + (png ? dir.file("h.png") : ""));
        EXPECT_EQ(r.exitCode, 0) << name << ": " << r.output;
        nlohmann::json json;
        test::expectSameMesh(test::readGlb(dir.file(name), &json), ply, name, true);
        EXPECT_EQ(json["extensionsRequired"], nlohmann::json::array({"EXT_meshopt_compression"}));
    }
    test::expectSameTriangles(test::readStl(dir.file("h.stl")), ply, "STL");
    test::expectSameMesh(test::readGlb(dir.file("h.glb")), ply, "GLB");
    test::expectSameMesh(test::readVtp(dir.file("h.vtp")), ply, "VTP");

    auto r = runVdiso(extract + dir.file("x.ply") + " --mesh-compress");
    EXPECT_EQ(r.exitCode, 2);
    EXPECT_TRUE(contains(r.output, "--mesh-compress applies to a .glb mesh output")) << r.output;
    EXPECT_EQ(runVdiso("extract " + store + " --iso 600.5 --mesh-compress").exitCode, 2);
    r = runVdiso(extract + dir.file("x.stp"));
    EXPECT_EQ(r.exitCode, 1);
    EXPECT_TRUE(contains(r.output, "x.stp: unknown mesh format (expected a .ply, .obj, .stl, .glb or .vtp name)"))
        << r.output;
    EXPECT_FALSE(std::filesystem::exists(dir.file("x.ply")));
    EXPECT_FALSE(std::filesystem::exists(dir.file("x.stp")));
    for (const char* name : {"h.stl", "h.glb", "h.vtp"}) {
        test::writeFile(dir.file(name), "old");
        r = runVdiso(extract + dir.file(name));
        EXPECT_EQ(r.exitCode, 2) << name;
        EXPECT_TRUE(contains(r.output, "already exists")) << r.output;
        EXPECT_EQ(test::readFile(dir.file(name)).size(), 3u) << name;
    }
    EXPECT_EQ(runVdiso(extract + dir.file("h.glb") + " --force --mesh-compress").exitCode, 0);
    EXPECT_EQ(test::readGlb(dir.file("h.glb")).triangleCount(), ply.triangleCount());
}

// --smooth, --decimate, --largest and --min-piece from the command line: into every streamed
// format and into the picture, with their figures; what they refuse.
TEST(CliExtract, PostProcessesTheMesh) {
    test::ScratchDir dir;
    const std::string store = dir.file("h.vdiso");
    ASSERT_EQ(runVdiso("synth " + store + " --kind head --size 48 --brick 8 --quiet").exitCode, 0);
    const std::string extract = "extract " + store + " --iso 600.5 --quiet ";
    ASSERT_EQ(runVdiso(extract + "-o " + dir.file("plain.ply")).exitCode, 0);
    const TriangleMesh plain = test::readPly(dir.file("plain.ply"));
    const std::string post = " --smooth 3 --decimate 0.5 --min-piece 20 --stats " + dir.file("s.json");
    auto r = runVdiso(extract + "-o " + dir.file("p.ply") + post);
    ASSERT_EQ(r.exitCode, 0) << r.output;
    const nlohmann::json stats = nlohmann::json::parse(test::readFile(dir.file("s.json")));
    const TriangleMesh ply = test::readPly(dir.file("p.ply"));
    EXPECT_EQ(stats["triangles"], ply.triangleCount());
    EXPECT_EQ(stats["triangles_extracted"], plain.triangleCount());
    EXPECT_EQ(stats["smooth"], 3);
    EXPECT_GE(stats["pieces"].get<int>(), 1);
    EXPECT_LT(ply.triangleCount(), plain.triangleCount() * 6 / 10);
    EXPECT_GT(ply.triangleCount(), plain.triangleCount() * 4 / 10);
    // The same mesh in another format, and held for a picture.
    r = runVdiso(extract + "-o " + dir.file("p.stl") + post + " --force");
    ASSERT_EQ(r.exitCode, 0) << r.output;
    EXPECT_EQ(test::readStl(dir.file("p.stl")).normals.size(), ply.triangleCount());
    r = runVdiso(extract + "-o " + dir.file("held.ply") + " --png " + dir.file("p.png") + post + " --force");
    ASSERT_EQ(r.exitCode, 0) << r.output;
    test::expectSameMesh(test::readPly(dir.file("held.ply")), ply, "held for the picture");
    r = runVdiso(extract + "-o " + dir.file("l.ply") + " --largest --method noise");
    ASSERT_EQ(r.exitCode, 0) << r.output;
    EXPECT_LE(test::readPly(dir.file("l.ply")).triangleCount(), plain.triangleCount());
    // No file is left beside the outputs.
    size_t files = 0;
    for (const auto& e : std::filesystem::directory_iterator(dir.path())) files += e.is_regular_file();
    EXPECT_EQ(files, 8u);  // h.vdiso, plain.ply, p.ply, s.json, p.stl, held.ply, p.png, l.ply

    const std::pair<const char*, const char*> refused[] = {
        {" --smooth 2 --method sage -o x.ply", "apply to the full surface"},
        {" --decimate 0 -o x.ply", "--decimate expects the fraction"},
        {" --decimate 1.5 -o x.ply", "--decimate expects the fraction"},
        {" --min-piece 0 -o x.ply", "--min-piece"},
        {" --smooth -1 -o x.ply", "--smooth"},
        {" --largest", "give -o MESH or --png"},
        {" --largest --path orbit:3 --png f%d.png", "nor post-processes them"},
    };
    for (const auto& [options, message] : refused) {
        r = runVdiso(extract + options);
        EXPECT_EQ(r.exitCode, 2) << options;
        EXPECT_TRUE(contains(r.output, message)) << options << ": " << r.output;
    }
    // Every piece dropped: an empty mesh, and a warning that says why.
    r = runVdiso(extract + "-o " + dir.file("none.ply") + " --min-piece 100000000");
    EXPECT_EQ(r.exitCode, 0) << r.output;
    EXPECT_TRUE(contains(r.output, "dropped every piece (the largest has")) << r.output;
    EXPECT_EQ(test::readPly(dir.file("none.ply")).triangleCount(), 0u);
    // An existing output stays as it was.
    test::writeFile(dir.file("old.ply"), "old");
    r = runVdiso(extract + "-o " + dir.file("old.ply") + " --smooth 2");
    EXPECT_EQ(r.exitCode, 2);
    EXPECT_TRUE(contains(r.output, "already exists")) << r.output;
    EXPECT_EQ(test::readFile(dir.file("old.ply")).size(), 3u);
}

TEST(CliExtract, BadArgumentsAreUsageErrors) {
    test::ScratchDir dir;
    const std::string store = dir.file("h.vdiso");
    ASSERT_EQ(test::runVdiso("synth " + store + " --kind head --size 24 --quiet").exitCode, 0);
    EXPECT_EQ(test::runVdiso("extract " + store).exitCode, 2);  // no --iso
    EXPECT_EQ(test::runVdiso("extract " + store + " --iso 1 --method marching").exitCode, 2);
    EXPECT_EQ(test::runVdiso("extract " + store + " --iso 1 -o x.stp").exitCode, 1);
    EXPECT_EQ(test::runVdiso("extract " + store + " --iso 1 --view sideways --png " + dir.file("a.png")).exitCode, 2);
    // A meta-cell's row of corners is one 64-bit word: 32 cells at most.
    const auto big = test::runVdiso("extract " + store + " --iso 1 --metacell 33");
    EXPECT_EQ(big.exitCode, 2);
    EXPECT_NE(big.output.find("--metacell must be between 1 and 32, not 33"), std::string::npos) << big.output;
    EXPECT_EQ(test::runVdiso("extract " + store + " --iso 1 --metacell 32").exitCode, 0);
    EXPECT_EQ(test::runVdiso("extract " + store + " --iso 1 --readers 0").exitCode, 2);
    // Image strips pin bricks: a cache too small for them is refused before anything is read
    // (13^3 bricks of 16 cells, 13.7 KB each: 1 MB holds 76, enough for 19 strips, not 20).
    const std::string bricks = dir.file("b.vdiso");
    ASSERT_EQ(test::runVdiso("synth " + bricks + " --kind head --size 200 --brick 16 --quiet").exitCode, 0);
    const auto strips = test::runVdiso("extract " + bricks + " --iso 600.5 --method sage --cache-mb 1 --threads 20");
    EXPECT_EQ(strips.exitCode, 2);
    EXPECT_NE(strips.output.find("20 image strips need a brick cache of 80 bricks; it holds 76 of 13 KB (--cache-mb)"),
              std::string::npos) << strips.output;
    EXPECT_EQ(test::runVdiso("extract " + bricks + " --iso 600.5 --method sage --cache-mb 1 --threads 19").exitCode, 0);
    const auto r = test::runVdiso("extract " + dir.file("missing.vdiso") + " --iso 1");
    EXPECT_EQ(r.exitCode, 1);
    EXPECT_NE(r.output.find("missing.vdiso: cannot open"), std::string::npos) << r.output;
}


// Without --threads every core works, for every method; --threads 1 is the one-thread path; a
// cache too small for a strip per core gets fewer strips, not an error.
TEST(CliExtract, ThreadsDefaultToTheMachinesCores) {
    test::ScratchDir dir;
    const std::string store = dir.file("h.vdiso");
    ASSERT_EQ(test::runVdiso("synth " + store + " --kind head --size 64 --brick 16 --quiet").exitCode, 0);
    const std::string cores = "\"threads\": " + std::to_string(std::max(1u, std::thread::hardware_concurrency()));
    for (const char* method : {"octree", "noise", "sage", "wise"}) {
        const auto r = test::runVdiso("extract " + store + " --iso 600.5 --method " + method + " --stats -");
        ASSERT_EQ(r.exitCode, 0) << r.output;
        EXPECT_NE(r.output.find(cores), std::string::npos) << method << ": " << r.output;
        const auto one = test::runVdiso("extract " + store + " --iso 600.5 --method " + method + " --threads 1 --stats -");
        EXPECT_NE(one.output.find("\"threads\": 1,"), std::string::npos) << method << ": " << one.output;
    }
    // 1 MB holds 76 bricks of 16 cells (13.7 KB): 19 strips; the default takes what fits.
    const auto small = test::runVdiso("extract " + store + " --iso 600.5 --method sage --cache-mb 1 --stats -");
    EXPECT_EQ(small.exitCode, 0) << small.output;
}

// Threads reading ahead: the default 2, but no more than the cores beside the extraction's
// own thread, at least one; --readers as given.
TEST(CliExtract, ReadersDefaultToTheCoresBesideTheExtraction) {
    test::ScratchDir dir;
    const std::string store = dir.file("h.vdiso");
    ASSERT_EQ(test::runVdiso("synth " + store + " --kind head --size 64 --brick 16 --quiet").exitCode, 0);
    const int cores = int(std::max(1u, std::thread::hardware_concurrency()));
    const std::string readers = "\"readers\": " + std::to_string(std::clamp(cores - 1, 1, 2)) + ",";
    for (const char* method : {"octree", "sage"}) {
        const auto r = test::runVdiso("extract " + store + " --iso 600.5 --method " + method + " --threads 1 --stats -");
        ASSERT_EQ(r.exitCode, 0) << r.output;
        EXPECT_NE(r.output.find(readers), std::string::npos) << method << ": " << r.output;
        const auto asked = test::runVdiso("extract " + store + " --iso 600.5 --method " + method + " --readers 3 --stats -");
        EXPECT_NE(asked.output.find("\"readers\": 3,"), std::string::npos) << method << ": " << asked.output;
    }
}

TEST(CliExtract, OrbitPathWritesAStatsLineAndAPicturePerFrame) {
    test::ScratchDir dir;
    const std::string store = dir.file("h.vdiso"), stats = dir.file("path.jsonl");
    ASSERT_EQ(test::runVdiso("synth " + store + " --kind head --size 48 --brick 8 --quiet").exitCode, 0);
    auto r = test::runVdiso("extract " + store + " --iso 600.5 --method sage --path orbit:3 --size 64x64 --png " +
                            dir.file("f_%02d.png") + " --stats " + stats + " --quiet");
    ASSERT_EQ(r.exitCode, 0) << r.output;
    const auto bytes = test::readFile(stats);
    const std::string text(bytes.begin(), bytes.end());
    EXPECT_EQ(std::count(text.begin(), text.end(), '\n'), 3);
    for (int f = 0; f < 3; ++f) {
        EXPECT_NE(text.find("\"frame\": " + std::to_string(f)), std::string::npos) << text;
        EXPECT_TRUE(std::filesystem::exists(dir.file("f_0" + std::to_string(f) + ".png")));
    }
    // The cache is kept: the first frame reads bricks; the path as a whole reads each at most once.
    std::vector<long> loaded;
    for (size_t at = text.find("\"bricks_loaded\": "); at != std::string::npos;
         at = text.find("\"bricks_loaded\": ", at + 1))
        loaded.push_back(std::stol(text.substr(at + 17)));
    ASSERT_EQ(loaded.size(), 3u);
    EXPECT_GT(loaded[0], 0);
    EXPECT_LE(loaded[0] + loaded[1] + loaded[2], long(BrickStoreReader(store).layout().brickCount()));
    // Frames fill the arrays the frame before handed back (ExtractSession::recycle): a camera
    // seen again after another one gives the same picture, byte for byte.
    const std::string cams = dir.file("cams.json");
    {
        std::FILE* f = std::fopen(cams.c_str(), "w");
        ASSERT_NE(f, nullptr);
        std::fputs("[{\"eye\": [150, 24, 24], \"target\": [24, 24, 24], \"up\": [0, 0, 1], \"fov\": 30},"
                   " {\"eye\": [24, 150, 60], \"target\": [24, 24, 24], \"up\": [0, 0, 1], \"fov\": 30},"
                   " {\"eye\": [150, 24, 24], \"target\": [24, 24, 24], \"up\": [0, 0, 1], \"fov\": 30}]",
                   f);
        std::fclose(f);
    }
    r = test::runVdiso("extract " + store + " --iso 600.5 --method sage --path " + cams + " --size 64x64 --png " +
                       dir.file("g_%d.png") + " --quiet");
    ASSERT_EQ(r.exitCode, 0) << r.output;
    EXPECT_EQ(test::readFile(dir.file("g_0.png")), test::readFile(dir.file("g_2.png")));
    EXPECT_NE(test::readFile(dir.file("g_0.png")), test::readFile(dir.file("g_1.png")));
    r = test::runVdiso("extract " + store + " --iso 600.5 --method sage --path orbit:3 --png " + dir.file("f.png"));
    EXPECT_EQ(r.exitCode, 2);
    EXPECT_NE(r.output.find("%d"), std::string::npos) << r.output;
    r = test::runVdiso("extract " + store + " --iso 600.5 --method sage --path orbit:3 -o " + dir.file("m.ply"));
    EXPECT_EQ(r.exitCode, 2);
}

// vdiso serve reads its numbers and leaves their ranges to the server, which checks them once,
// before opening a store: out of range, the flag is named and nothing is served (exit 2).
TEST(CliServe, SettingsOutOfRangeNameTheFlag) {
    test::ScratchDir dir;
    const std::string store = dir.file("h.vdiso");
    ASSERT_EQ(test::runVdiso("synth " + store + " --kind head --size 24 --quiet").exitCode, 0);
    for (const std::string bad : {"--threads 0", "--threads 65", "--metacell 33", "--max-viewers 100001", "--lod-error -1"}) {
        // A server that started would run until killed: the timeout ends it (exit 124).
        const auto r = test::runCommand("timeout 20 " + std::string(VDISO_BINARY) + " serve " + store +
                                        " --host 127.0.0.1 --port 0 " + bad);
        EXPECT_EQ(r.exitCode, 2) << bad << ": " << r.output;
        EXPECT_NE(r.output.find(bad.substr(0, bad.find(' ')) + " expects"), std::string::npos) << bad << ": " << r.output;
    }
}

}  // namespace
}  // namespace vdiso
