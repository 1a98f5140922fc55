// vdiso-mpi convert under mpirun: the store equals vdiso convert's in every header field,
// entry, sub-block code, histogram count and brick byte (only where bricks lie differs), for a
// raw input (each rank seeks to its slab), a gzip NRRD (each rank decompresses up to it), u8,
// u16 and f32, with coarse levels that have fewer layers than there are ranks and a rank
// without level-0 layers; every rank does a real share; a failure on one rank (its input
// truncated, missing or different) fails the job naming it, with no output and no temporary
// file left; existing outputs and bad options are refused. Built only when MPI was found.
#ifdef VDISO_MPI_COMMAND

#include <gtest/gtest.h>

#include <algorithm>
#include <bit>
#include <filesystem>
#include <numeric>
#include <string>
#include <vector>

#include "io/store/brick_store.h"
#include "tests/mpi_test_util.h"
#include "tests/reader_test_util.h"
#include "tests/test_util.h"

namespace vdiso {
namespace {

using test::numbers;
using test::readText;
using test::runMpi;

std::vector<unsigned char> storedBytes(const BrickStoreReader& store, int64_t id) {
    const std::span<const unsigned char> s = store.readStoredBrick(id);
    return {s.begin(), s.end()};
}

// The two stores are equal in everything but where their bricks lie, and the bricks of
// `mpi` do not overlap.
void expectSameStore(const std::string& single, const std::string& mpi) {
    const BrickStoreReader a(single), b(mpi);
    const StoreHeader &h = a.header(), &g = b.header();
    EXPECT_EQ(h.formatVersion, g.formatVersion);
    EXPECT_EQ(h.volume.dims, g.volume.dims);
    EXPECT_EQ(h.volume.type, g.volume.type);
    EXPECT_EQ(h.volume.spacing, g.volume.spacing);
    EXPECT_EQ(h.volume.origin, g.volume.origin);
    EXPECT_EQ(h.volume.hasOrientation, g.volume.hasOrientation);
    EXPECT_EQ(h.volume.direction, g.volume.direction);
    EXPECT_EQ(h.brickSize, g.brickSize);
    EXPECT_EQ(h.levelCount, g.levelCount);
    EXPECT_EQ(h.compression, g.compression);
    EXPECT_EQ(h.checksum, g.checksum);
    EXPECT_EQ(h.filter, g.filter);
    EXPECT_EQ(h.valueMin, g.valueMin);
    EXPECT_EQ(h.valueMax, g.valueMax);
    EXPECT_EQ(h.storedBrickBytes, g.storedBrickBytes);
    // (The index's stored size is not compared: its parts are compressed, and the bricks'
    // offsets in it differ, as the ranks write them in another order.)

    EXPECT_EQ(a.histogram().lo, b.histogram().lo);
    EXPECT_EQ(a.histogram().hi, b.histogram().hi);
    EXPECT_EQ(a.histogram().counts, b.histogram().counts);

    ASSERT_EQ(a.index().size(), b.index().size());
    ASSERT_GT(a.levels().size(), 2u) << "the test volume should have coarse levels";
    for (size_t id = 0; id < a.index().size(); ++id) {
        const BrickEntry &e = a.index()[id], &f = b.index()[id];
        ASSERT_EQ(e.storedBytes, f.storedBytes) << "brick " << id;
        ASSERT_EQ(e.checksum, f.checksum) << "brick " << id;
        ASSERT_EQ(std::bit_cast<uint32_t>(e.minValue), std::bit_cast<uint32_t>(f.minValue)) << "brick " << id;
        ASSERT_EQ(std::bit_cast<uint32_t>(e.maxValue), std::bit_cast<uint32_t>(f.maxValue)) << "brick " << id;
        ASSERT_EQ(e.compressed, f.compressed) << "brick " << id;
        ASSERT_EQ(storedBytes(a, int64_t(id)), storedBytes(b, int64_t(id))) << "brick " << id;
    }
    ASSERT_EQ(a.subBlockCodes().size(), b.subBlockCodes().size());
    for (size_t k = 0; k < a.subBlockCodes().size(); ++k) {
        ASSERT_EQ(a.subBlockCodes()[k].lo, b.subBlockCodes()[k].lo) << "code " << k;
        ASSERT_EQ(a.subBlockCodes()[k].hi, b.subBlockCodes()[k].hi) << "code " << k;
    }
    // The ranks wrote disjoint regions.
    std::vector<BrickEntry> entries(b.index().begin(), b.index().end());
    std::sort(entries.begin(), entries.end(), [](const BrickEntry& x, const BrickEntry& y) { return x.offset < y.offset; });
    for (size_t k = 0; k + 1 < entries.size(); ++k) {
        ASSERT_EQ(entries[k].offset % kStoreAlignment, 0u);
        ASSERT_LE(entries[k].offset + entries[k].storedBytes, entries[k + 1].offset);
    }
}

// Nothing but `keep` in the scratch directory: no output, no temporary, no side file.
void expectOnly(const test::ScratchDir& dir, const std::vector<std::string>& keep) {
    for (const auto& entry : std::filesystem::directory_iterator(dir.path())) {
        const std::string name = entry.path().filename().string();
        EXPECT_NE(std::find(keep.begin(), keep.end(), name), keep.end()) << "left behind: " << name;
    }
}

// `values` of one byte each, little-endian NRRD with gzip encoding, header attached.
std::string gzipNrrd(const std::vector<unsigned char>& raw, const Dims3& d, const char* type) {
    const std::string header = std::string("NRRD0004\ntype: ") + type + "\ndimension: 3\nsizes: " +
                               std::to_string(d[0]) + " " + std::to_string(d[1]) + " " + std::to_string(d[2]) +
                               "\nencoding: gzip\nendian: little\n\n";
    return header + test::gzipBytes(std::string(raw.begin(), raw.end()));
}

// Converts `input` (with `inputArgs`) once with vdiso and once with `ranks` ranks, expects the
// same store, and returns the MPI job's statistics.
std::string convertBothWays(const test::ScratchDir& dir, const std::string& input, const std::string& args,
                            int ranks) {
    const std::string one = dir.file("one.vdiso"), many = dir.file("many.vdiso"), stats = dir.file("s.json");
    std::filesystem::remove(one);
    std::filesystem::remove(many);
    std::filesystem::remove(stats);
    auto r = test::runVdiso("convert " + input + " " + one + " " + args + " --quiet");
    EXPECT_EQ(r.exitCode, 0) << r.output;
    r = runMpi(ranks, "convert " + input + " " + many + " " + args + " --stats " + stats);
    EXPECT_EQ(r.exitCode, 0) << r.output;
    EXPECT_NE(r.output.find("wrote " + many + " on " + std::to_string(ranks) + " ranks: "), std::string::npos)
        << r.output;
    expectSameStore(one, many);
    return std::filesystem::exists(stats) ? readText(stats) : std::string();
}

// Every rank did a real share: a run of layers, read its slab (skipping to it), wrote bricks;
// the shares add up to the totals.
void expectRealShares(const std::string& json, int ranks, uint64_t layers) {
    EXPECT_EQ(numbers(json, "ranks"), std::vector<uint64_t>{uint64_t(ranks)}) << json;
    const auto first = numbers(json, "first_layer"), count = numbers(json, "layers"),
               read = numbers(json, "bytes_read"), skipped = numbers(json, "slices_skipped"),
               bricks = numbers(json, "bricks_written"), bytes = numbers(json, "bytes_written"),
               total = numbers(json, "bricks"), level0 = numbers(json, "level0_bytes"),
               coarse = numbers(json, "coarse_bytes"), input = numbers(json, "input_bytes");
    ASSERT_EQ(first.size(), size_t(ranks)) << json;
    ASSERT_EQ(read.size(), size_t(ranks) + 1) << json;  // the total first
    ASSERT_EQ(bricks.size(), size_t(ranks)) << json;
    uint64_t next = 0, sumBricks = 0, sumBytes = 0, sumRead = 0;
    for (int k = 0; k < ranks; ++k) {
        SCOPED_TRACE("rank " + std::to_string(k));
        EXPECT_EQ(first[size_t(k)], next);
        EXPECT_GT(count[size_t(k)], 0u);
        EXPECT_GT(read[size_t(k) + 1], 0u);
        EXPECT_GT(bricks[size_t(k)], 0u);
        EXPECT_EQ(skipped[size_t(k)] > 0, k > 0);
        next += count[size_t(k)];
        sumBricks += bricks[size_t(k)];
        sumBytes += bytes[size_t(k)];
        sumRead += read[size_t(k) + 1];
    }
    EXPECT_EQ(next, layers);
    EXPECT_EQ(sumBricks, total.at(0));
    EXPECT_EQ(sumBytes, level0.at(0) + coarse.at(0));
    EXPECT_EQ(sumRead, read.at(0));
    // The input once, plus the few ghost slices neighbours both read.
    EXPECT_GE(read.at(0), input.at(0));
    EXPECT_LT(read.at(0), input.at(0) + input.at(0) / 4);
}

TEST(MpiConvert, HeadU16RawIsTheSingleProcessStore) {
    test::ScratchDir dir;
    const std::string raw = dir.file("head.raw");
    ASSERT_EQ(test::runVdiso("synth " + raw + " --kind head --size 60,52,100 --type u16 --quiet").exitCode, 0);
    // 13 layers of 8-cell bricks: 5, 4, 4 per rank; 5 levels, the coarsest two with fewer
    // layers than ranks.
    const std::string json = convertBothWays(dir, raw, "--dims 60,52,100 --type u16 --brick 8", 3);
    expectRealShares(json, 3, 13);
    EXPECT_EQ(numbers(json, "levels"), std::vector<uint64_t>{5}) << json;
    uint64_t halo = 0;
    for (uint64_t h : numbers(json, "halo_bytes_sent")) halo += h;
    EXPECT_GT(halo, 0u) << json;
}

TEST(MpiConvert, TurbulenceU8GzipNrrdIsTheSingleProcessStore) {
    test::ScratchDir dir;
    const std::string raw = dir.file("t.raw"), nrrd = dir.file("t.nrrd");
    ASSERT_EQ(test::runVdiso("synth " + raw + " --kind turbulence --size 40,36,66 --type u8 --quiet").exitCode, 0);
    test::writeFile(nrrd, gzipNrrd(test::readFile(raw), {40, 36, 66}, "uint8"));
    // 9 layers: 3 per rank, each but the first decompressing the stream up to its slab.
    expectRealShares(convertBothWays(dir, nrrd, "--brick 8 --compress zstd", 3), 3, 9);
}

TEST(MpiConvert, F32WithMoreRanksThanLayersAndOneRank) {
    test::ScratchDir dir;
    const std::string raw = dir.file("f.raw");
    ASSERT_EQ(test::runVdiso("synth " + raw + " --kind turbulence --size 37,30,20 --type f32 --quiet").exitCode, 0);
    const std::string args = "--dims 37,30,20 --type f32 --brick 8";
    // 3 layers among 4 ranks: the last has none at any level.
    const std::string json = convertBothWays(dir, raw, args, 4);
    EXPECT_EQ(numbers(json, "layers"), (std::vector<uint64_t>{1, 1, 1, 0})) << json;
    EXPECT_EQ(numbers(json, "bricks_written").at(3), 0u) << json;
    EXPECT_EQ(numbers(json, "bytes_read").at(4), 0u) << json;
    // One rank holds every coarse level itself.
    expectRealShares(convertBothWays(dir, raw, args + " --levels 2 --no-shuffle", 1), 1, 3);
}

TEST(MpiConvert, FailureOnOneRankFailsTheJobWithoutOutput) {
    test::ScratchDir dir;
    const std::string raw = dir.file("t.raw"), nrrd = dir.file("t.nrrd"), out = dir.file("out.vdiso"),
                      stats = dir.file("s.json");
    ASSERT_EQ(test::runVdiso("synth " + raw + " --kind turbulence --size 40,36,90 --type u8 --quiet").exitCode, 0);
    // The compressed stream cut at 85%: ranks 0 and 1 read their slabs, rank 2 meets the end.
    std::string bytes = gzipNrrd(test::readFile(raw), {40, 36, 90}, "uint8");
    bytes.resize(bytes.size() * 85 / 100);
    test::writeFile(nrrd, bytes);
    auto r = runMpi(3, "convert " + nrrd + " " + out + " --brick 8 --stats " + stats);
    EXPECT_EQ(r.exitCode, 1) << r.output;
    EXPECT_NE(r.output.find("vdiso-mpi convert: rank 2: " + nrrd + ": "), std::string::npos) << r.output;
    EXPECT_NE(r.output.find("truncated"), std::string::npos) << r.output;
    EXPECT_EQ(r.output.find("vdiso-mpi convert: "), r.output.rfind("vdiso-mpi convert: ")) << r.output;
    expectOnly(dir, {"t.raw", "t.nrrd"});

    // The input missing on one node (rank 2), or another volume there (rank 1).
    const std::string args = " --dims 40,36,90 --type u8 --brick 8 " + out;
    r = test::runMpiGroups({{2, "convert " + raw + args}, {1, "convert " + dir.file("none.raw") + args}});
    EXPECT_EQ(r.exitCode, 1) << r.output;
    EXPECT_NE(r.output.find("vdiso-mpi convert: rank 2: " + dir.file("none.raw") + ": cannot open"), std::string::npos)
        << r.output;
    expectOnly(dir, {"t.raw", "t.nrrd"});
    const std::string other = dir.file("other.raw");
    ASSERT_EQ(test::runVdiso("synth " + other + " --kind turbulence --size 40,36,90 --type u8 --seed 2 --quiet").exitCode, 0);
    r = test::runMpiGroups({{1, "convert " + raw + args},
                            {1, "convert " + other + " --dims 40,36,89 --type u8 --brick 8 " + out + " --header-bytes 1440"},
                            {1, "convert " + raw + args}});
    EXPECT_EQ(r.exitCode, 1) << r.output;
    EXPECT_NE(r.output.find("vdiso-mpi convert: rank 1: " + other + ": is 40 x 36 x 89 u8"), std::string::npos)
        << r.output;
    EXPECT_NE(r.output.find("on rank 0: every rank must read the same input"), std::string::npos) << r.output;
    expectOnly(dir, {"t.raw", "t.nrrd", "other.raw"});

    // A raw file too short for its dimensions: refused at open, by every rank.
    r = runMpi(3, "convert " + raw + " --dims 40,36,91 --type u8 " + out);
    EXPECT_EQ(r.exitCode, 1) << r.output;
    EXPECT_NE(r.output.find("vdiso-mpi convert: rank 0: " + raw + ": file is 1440 bytes shorter"), std::string::npos)
        << r.output;
    expectOnly(dir, {"t.raw", "t.nrrd", "other.raw"});
}

TEST(MpiConvert, RefusalsLeaveOutputsUntouched) {
    test::ScratchDir dir;
    const std::string raw = dir.file("h.raw"), out = dir.file("h.vdiso");
    ASSERT_EQ(test::runVdiso("synth " + raw + " --kind head --size 24 --type u16 --quiet").exitCode, 0);
    const std::string input = raw + " --dims 24,24,24 --type u16 ";
    test::writeFile(out, std::string("keep"));
    auto r = runMpi(2, "convert " + input + out);
    EXPECT_EQ(r.exitCode, 2) << r.output;
    EXPECT_NE(r.output.find("already exists"), std::string::npos) << r.output;
    EXPECT_EQ(readText(out), "keep");
    // Bad options: the same on every rank, one message, exit 2.
    for (const char* bad : {"--brick 1", "--levels 9", "--frobnicate"}) {
        r = runMpi(2, "convert " + input + dir.file("x.vdiso") + " " + bad);
        EXPECT_EQ(r.exitCode, 2) << bad << ": " << r.output;
        EXPECT_EQ(r.output.find("vdiso-mpi convert: "), r.output.rfind("vdiso-mpi convert: ")) << r.output;
        EXPECT_NE(r.output.find("see 'vdiso-mpi convert --help'"), std::string::npos) << r.output;
        if (std::string(bad) == "--levels 9") {
            EXPECT_NE(r.output.find("at most 0 coarser levels"), std::string::npos) << r.output;
        }
    }
    r = runMpi(2, "convert " + input + raw);  // the input as output
    EXPECT_EQ(r.exitCode, 2) << r.output;
    EXPECT_NE(r.output.find("INPUT and OUTPUT are the same file"), std::string::npos) << r.output;
    expectOnly(dir, {"h.raw", "h.vdiso"});
    r = runMpi(2, "convert " + input + out + " --force --quiet");
    EXPECT_EQ(r.exitCode, 0) << r.output;
    EXPECT_EQ(r.output, "");
    EXPECT_EQ(BrickStoreReader(out).volume().dims, (Dims3{24, 24, 24}));
    expectOnly(dir, {"h.raw", "h.vdiso"});
    r = runMpi(2, "convert --help");
    EXPECT_EQ(r.exitCode, 0);
    EXPECT_EQ(r.output.find("usage: mpirun -np N vdiso-mpi convert"), r.output.rfind("usage: mpirun -np N vdiso-mpi convert"));
}

}  // namespace
}  // namespace vdiso

#endif  // VDISO_MPI_COMMAND
