// The brick store: round trips of every type with every sample (ghosts included) checked, index
// statistics against brute force, and refusal of damaged files at every kind of damage.
#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstring>

#include "core/brick_layout.h"
#include "core/synth/synth.h"
#include "io/crc32.h"
#include "io/store/brick_store.h"
#include "io/store/byte_shuffle.h"
#include "io/error.h"
#include "io/store/store_format.h"
#include "io/store/store_writer.h"
#include "io/readers/volume_open.h"
#include "tests/reader_test_util.h"
#include "tests/test_util.h"

namespace vdiso {
namespace {

using test::MemoryVolume;
using test::ScratchDir;

struct RoundTripCase {
    ScalarType type;
    Dims3 dims;
    int brick;
    Compression compression;
};

class StoreRoundTrip : public ::testing::TestWithParam<RoundTripCase> {};

TEST_P(StoreRoundTrip, EverySampleAndGhostSurvives) {
    const RoundTripCase& rc = GetParam();
    ScratchDir dir;
    MemoryVolume volume(rc.dims, rc.type);
    StoreWriteOptions o;
    o.brickSize = rc.brick;
    o.compression = rc.compression;
    const std::string path = dir.file("v.vdiso");
    const StoreWriteSummary s = writeBrickStore(volume, path, o);

    const BrickStoreReader store(path);
    EXPECT_EQ(store.volume().dims, rc.dims);
    EXPECT_EQ(store.volume().type, rc.type);
    EXPECT_EQ(store.header().brickSize, rc.brick);
    EXPECT_EQ(int64_t(store.index().size()), s.bricks);  // every level's
    EXPECT_EQ(store.fileBytes(), s.fileBytes);
    for (const BrickEntry& e : store.index()) EXPECT_EQ(e.offset % kStoreAlignment, 0u);
    EXPECT_EQ(test::compareStoreWithSamples(store, volume.bytes()), "");
    // Every coarser level, until one brick, against a brute-force downsample of the level below.
    ASSERT_EQ(store.header().levelCount, levelsUntilOneBrick(store.layout()));
    std::vector<unsigned char> level = volume.bytes();
    Dims3 dims = rc.dims;
    for (int l = 1; l < store.header().levelCount; ++l) {
        level = test::bruteForceLevel(level, dims, rc.type);
        EXPECT_EQ(store.levels()[size_t(l)].volume.dims, dims) << "level " << l;
        EXPECT_EQ(test::compareStoreWithSamples(store, level, l), "") << "level " << l;
    }

    // The histogram counts every sample exactly once.
    uint64_t total = 0;
    for (uint64_t c : store.histogram().counts) total += c;
    EXPECT_EQ(total, uint64_t(volume.info().sampleCount()));
    double lo = INFINITY, hi = -INFINITY;
    for (int64_t z = 0; z < rc.dims[2]; ++z)
        for (int64_t y = 0; y < rc.dims[1]; ++y)
            for (int64_t x = 0; x < rc.dims[0]; ++x) {
                lo = std::min(lo, volume.at(x, y, z));
                hi = std::max(hi, volume.at(x, y, z));
            }
    EXPECT_EQ(store.header().valueMin, lo);
    EXPECT_EQ(store.header().valueMax, hi);
}

INSTANTIATE_TEST_SUITE_P(
    Types, StoreRoundTrip,
    ::testing::Values(RoundTripCase{ScalarType::U8, {19, 11, 14}, 4, Compression::Zstd},
                      RoundTripCase{ScalarType::I16, {19, 11, 14}, 4, Compression::Zstd},
                      RoundTripCase{ScalarType::U16, {19, 11, 14}, 4, Compression::Zstd},
                      RoundTripCase{ScalarType::F32, {19, 11, 14}, 4, Compression::Zstd},
                      RoundTripCase{ScalarType::U16, {17, 9, 9}, 8, Compression::None},
                      RoundTripCase{ScalarType::F32, {2, 2, 2}, 32, Compression::Zstd},
                      RoundTripCase{ScalarType::U8, {40, 33, 34}, 32, Compression::Zstd},
                      RoundTripCase{ScalarType::I16, {5, 6, 7}, 2, Compression::None},
                      RoundTripCase{ScalarType::U8, {19, 11, 14}, 4, Compression::Lz4},
                      RoundTripCase{ScalarType::U16, {19, 11, 14}, 4, Compression::Lz4},
                      RoundTripCase{ScalarType::F32, {40, 33, 34}, 32, Compression::Lz4}),
    [](const ::testing::TestParamInfo<RoundTripCase>& param) {
        const RoundTripCase& c = param.param;
        return std::string(scalarTypeName(c.type)) + "_" + std::to_string(c.dims[0]) + "x" +
               std::to_string(c.dims[1]) + "x" + std::to_string(c.dims[2]) + "_b" +
               std::to_string(c.brick) + "_" + compressionName(c.compression);
    });

TEST(StoreLayout, BricksCoverEveryCellOnce) {
    const BrickLayout l({100, 33, 65}, 32);
    EXPECT_EQ(l.brickCounts, (Dims3{4, 1, 2}));
    for (int a = 0; a < 3; ++a) {
        int64_t cells = 0, owned = 0;
        for (int64_t c = 0; c < l.brickCounts[a]; ++c) {
            cells += l.cellsOnAxis(a, c);
            owned += l.ownedSamplesOnAxis(a, c);
        }
        EXPECT_EQ(cells, l.dims[a] - 1);
        EXPECT_EQ(owned, l.dims[a]);
    }
    for (int64_t id = 0; id < l.brickCount(); ++id) {
        const Dims3 c = l.brickCoord(id);
        EXPECT_EQ(l.brickId(c[0], c[1], c[2]), id);
    }
}

// A small valid store to damage.
class DamagedStore : public ::testing::Test {
protected:
    void SetUp() override {
        MemoryVolume volume({21, 13, 12}, ScalarType::U16);
        StoreWriteOptions o;
        o.brickSize = 8;
        path = dir.file("good.vdiso");
        writeBrickStore(volume, path, o);
        bytes = test::readFile(path);
        header = BrickStoreReader(path).header();
    }
    // Writes `b` as a new file and returns the IoError message opening + reading it gives.
    std::string openError(const std::vector<unsigned char>& b) {
        return test::storeOpenError(dir.file("bad.vdiso"), b);
    }
    ScratchDir dir;
    std::string path;
    std::vector<unsigned char> bytes;
    StoreHeader header;
};

TEST_F(DamagedStore, WrongMagicIsRefused) {
    auto b = bytes;
    b[0] = 'X';
    const std::string msg = openError(b);
    EXPECT_NE(msg.find("bad.vdiso"), std::string::npos) << msg;
    EXPECT_NE(msg.find("not a vdiso brick store"), std::string::npos) << msg;
    EXPECT_NE(openError({'h', 'e', 'l', 'l', 'o'}).find("not a vdiso brick store"), std::string::npos);
}

TEST_F(DamagedStore, NewerVersionIsRefused) {
    auto b = bytes;
    const uint32_t version = kStoreFormatVersion + 1;
    std::memcpy(b.data() + 8, &version, 4);
    const std::string msg = openError(b);
    EXPECT_NE(msg.find("newer vdiso"), std::string::npos) << msg;
    EXPECT_NE(msg.find("reads up to version " + std::to_string(kStoreFormatVersion)), std::string::npos) << msg;
}

TEST_F(DamagedStore, TruncatedIndexIsRefused) {
    auto b = bytes;
    b.resize(b.size() - 10);
    const std::string msg = openError(b);
    EXPECT_NE(msg.find("index is missing or truncated"), std::string::npos) << msg;
}

TEST_F(DamagedStore, EveryTruncationIsRefused) {
    // Cutting the file anywhere must be detected at open: the index (or header) is last.
    for (size_t len = 0; len < bytes.size(); len += std::max<size_t>(1, bytes.size() / 97)) {
        std::vector<unsigned char> b(bytes.begin(), bytes.begin() + std::ptrdiff_t(len));
        EXPECT_NE(openError(b), "") << "truncated to " << len;
    }
}

TEST_F(DamagedStore, CorruptBrickIsReportedWithItsOffset) {
    BrickStoreReader store(path);
    const BrickEntry& e = store.index()[5];
    auto b = bytes;
    b[e.offset + e.storedBytes / 2] ^= 0x40;
    const std::string msg = openError(b);
    EXPECT_NE(msg.find("brick 5"), std::string::npos) << msg;
    EXPECT_NE(msg.find("byte offset " + std::to_string(e.offset)), std::string::npos) << msg;
    EXPECT_NE(msg.find("checksum mismatch"), std::string::npos) << msg;
}

// Neighbours in the file (x-neighbours in a row of bricks) read in one request give each
// brick's own bytes, in the order asked for; a corrupt one in the run is named as when read alone.
TEST_F(DamagedStore, NeighboursInTheFileReadTogether) {
    BrickStoreReader store(path);
    int runs = 0;
    for (int64_t id = 0; id + 1 < int64_t(store.index().size()); ++id) {
        if (!store.readsTogether(id, id + 1)) continue;
        EXPECT_TRUE(store.readsTogether(id + 1, id));
        ++runs;
        const std::vector<unsigned char> first(store.readStoredBrick(id).begin(), store.readStoredBrick(id).end());
        const std::vector<unsigned char> second(store.readStoredBrick(id + 1).begin(), store.readStoredBrick(id + 1).end());
        const int64_t backwards[2] = {id + 1, id};
        const auto both = store.readStoredBricks(backwards);
        EXPECT_TRUE(std::equal(both[0].begin(), both[0].end(), second.begin(), second.end())) << id;
        EXPECT_TRUE(std::equal(both[1].begin(), both[1].end(), first.begin(), first.end())) << id;
    }
    EXPECT_GE(runs, 6);  // 3 x 2 x 2 bricks, rows of 3 (layers are written in brick order)
    EXPECT_FALSE(store.readsTogether(int64_t(store.index().size()) - 1, int64_t(store.index().size())));
    EXPECT_FALSE(store.readsTogether(0, 0));
    int64_t apart = 0;  // a brick whose successor is elsewhere (levels are written interleaved)
    while (apart + 1 < int64_t(store.index().size()) && store.readsTogether(apart, apart + 1)) ++apart;
    ASSERT_LT(apart + 1, int64_t(store.index().size()));
    const int64_t far[2] = {apart, apart + 1};
    EXPECT_THROW(store.readStoredBricks(far), std::logic_error);

    const BrickEntry& e = store.index()[1];
    auto b = bytes;
    b[e.offset + e.storedBytes / 2] ^= 0x40;
    test::writeFile(dir.file("bad.vdiso"), b.data(), b.size());
    BrickStoreReader bad(dir.file("bad.vdiso"));
    try {
        const int64_t pair[2] = {0, 1};
        bad.readStoredBricks(pair);
        ADD_FAILURE() << "a corrupt brick in a run was read";
    } catch (const IoError& error) {
        EXPECT_NE(std::string(error.what()).find("brick 1"), std::string::npos) << error.what();
        EXPECT_NE(std::string(error.what()).find("checksum mismatch"), std::string::npos) << error.what();
    }
}

// Compressed bytes damaged before their checksum was taken (a writer's bug, or a bit flipped
// in memory before the write): the checksum passes, and where the damage breaks the stream's
// structure the decoder must report the brick rather than overrun or return a short brick.
// (Damaged literals decode without complaint: that is what the checksum is for.) Both codecs.
TEST(StoreDecode, MalformedCompressedBrickIsReportedNotReturned) {
    for (Compression codec : {Compression::Zstd, Compression::Lz4}) {
        test::ScratchDir dir;
        SynthParams p;
        p.kind = SynthKind::Head;
        p.dims = {40, 40, 40};
        const auto volume = openSynthVolume(p);
        StoreWriteOptions o;
        o.brickSize = 16;
        o.compression = codec;
        const std::string path = dir.file("v.vdiso");
        writeBrickStore(*volume, path, o);
        const BrickStoreReader good(path);
        const int64_t id = 3;
        const BrickEntry e = good.index()[size_t(id)];
        ASSERT_TRUE(e.compressed) << compressionName(codec);
        std::vector<unsigned char> b = test::readFile(path);
        // Overwrite the stream after its first bytes, then make both checksums agree.
        std::fill_n(b.begin() + std::ptrdiff_t(e.offset + 16), e.storedBytes - 16, uint8_t(0xff));
        const uint32_t brickCrc = crc32Of(b.data() + e.offset, e.storedBytes);
        b = test::rewriteStoreIndex(b, [&](std::vector<unsigned char>& index) {
            std::memcpy(index.data() + 16 + 32 * id + 12, &brickCrc, 4);
            const uint32_t indexCrc = crc32Of(index.data(), index.size() - 4);
            std::memcpy(index.data() + index.size() - 4, &indexCrc, 4);
        });
        test::writeFile(path, b.data(), b.size());
        const BrickStoreReader bad(path);
        std::vector<unsigned char> brick(bad.brickBytes());
        try {
            bad.readBrick(id, brick.data());
            ADD_FAILURE() << compressionName(codec) << ": a malformed brick was returned";
        } catch (const IoError& error) {
            const std::string msg = error.what();
            EXPECT_NE(msg.find("brick 3"), std::string::npos) << msg;
            EXPECT_TRUE(msg.find("cannot decompress") != std::string::npos ||
                        msg.find("wrong size") != std::string::npos) << msg;
        }
    }
}

TEST_F(DamagedStore, FlippedHeaderOrIndexByteIsRefused) {
    // Every header byte the checksum covers, and a sample of index bytes.
    for (size_t at = 0; at < 164; ++at) {
        auto b = bytes;
        b[at] ^= 0x01;
        EXPECT_NE(openError(b), "") << "header byte " << at;
    }
    for (uint64_t at = header.indexOffset; at < bytes.size(); at += 7) {
        auto b = bytes;
        b[at] ^= 0x10;
        EXPECT_NE(openError(b), "") << "index byte " << at;
    }
}

TEST(StoreWriter, FailedConversionLeavesNoFileAndKeepsTheOldOne) {
    ScratchDir dir;
    const std::string out = dir.file("out.vdiso");
    test::writeFile(out, "precious");
    MemoryVolume volume({9, 9, 9}, ScalarType::U8);
    // Existing output without overwrite: refused, untouched.
    EXPECT_THROW(writeBrickStore(volume, out, {}), IoError);
    EXPECT_EQ(test::readFile(out), std::vector<unsigned char>({'p', 'r', 'e', 'c', 'i', 'o', 'u', 's'}));
    // A progress callback that throws (an interrupt) mid-way: nothing left behind.
    const std::string fresh = dir.file("fresh.vdiso");
    StoreWriteOptions o;
    o.brickSize = 2;
    MemoryVolume volume2({9, 9, 9}, ScalarType::U8);
    EXPECT_THROW(writeBrickStore(volume2, fresh, o,
                                 [](double f) {
                                     if (f > 0.3) throw IoError("interrupted");
                                 }),
                 IoError);
    EXPECT_FALSE(std::filesystem::exists(fresh));
    size_t files = 0;
    for (const auto& entry : std::filesystem::directory_iterator(dir.path())) {
        (void)entry;
        ++files;
    }
    EXPECT_EQ(files, 1u) << "a temporary file was left behind";
}

TEST(StoreWriter, UnwritableOutputNamesThePath) {
    MemoryVolume volume({4, 4, 4}, ScalarType::U8);
    try {
        writeBrickStore(volume, "/nonexistent-dir/x.vdiso", {});
        FAIL() << "no error";
    } catch (const IoError& e) {
        EXPECT_NE(std::string(e.what()).find("/nonexistent-dir/x.vdiso: cannot write"),
                  std::string::npos)
            << e.what();
    }
}

TEST(StoreHistogram, QuantilesOfAKnownDistribution) {
    ScratchDir dir;
    // Values 0..255 repeated evenly: the median is about 128.
    MemoryVolume volume({16, 16, 16}, ScalarType::U8);
    writeBrickStore(volume, dir.file("h.vdiso"), {});
    const BrickStoreReader store(dir.file("h.vdiso"));
    EXPECT_NEAR(store.histogram().quantile(0.5), 128.0, 12.0);
    EXPECT_NEAR(store.histogram().quantile(0.0), 0.0, 2.0);
    EXPECT_NEAR(store.histogram().quantile(1.0), 255.0, 2.0);
}


TEST(ByteShuffle, UnshuffleInvertsShuffle) {
    for (size_t sampleBytes : {1u, 2u, 3u, 4u, 8u}) {
        const size_t n = 1001;
        std::vector<unsigned char> in(n * sampleBytes), planes(in.size()), back(in.size());
        for (size_t i = 0; i < in.size(); ++i) in[i] = uint8_t(i * 131 + 7);
        shuffleBytes(in.data(), n, sampleBytes, planes.data());
        // Plane k holds byte k of every sample.
        for (size_t i = 0; i < n; ++i)
            for (size_t k = 0; k < sampleBytes; ++k)
                ASSERT_EQ(planes[k * n + i], in[i * sampleBytes + k]);
        unshuffleBytes(planes.data(), n, sampleBytes, back.data());
        EXPECT_EQ(back, in) << sampleBytes;
    }
}

TEST(StoreWriter, ShuffleFilterIsRecordedAndOptional) {
    test::ScratchDir dir;
    for (bool shuffle : {true, false}) {
        for (ScalarType type : {ScalarType::U8, ScalarType::U16, ScalarType::F32}) {
            test::MemoryVolume volume({12, 10, 9}, type);
            StoreWriteOptions o;
            o.brickSize = 4;
            o.shuffle = shuffle;
            o.overwrite = true;
            writeBrickStore(volume, dir.file("s.vdiso"), o);
            const BrickStoreReader store(dir.file("s.vdiso"));
            const bool expectShuffle = shuffle && type != ScalarType::U8;
            EXPECT_EQ(store.header().filter,
                      expectShuffle ? BrickFilter::ByteShuffle : BrickFilter::None);
            EXPECT_EQ(test::compareStoreWithSamples(store, volume.bytes()), "");
        }
    }
}


// A source that records how far it has been read, to check conversion streams.
class CountingSource final : public SliceReader {
public:
    explicit CountingSource(const Dims3& dims) {
        mInfo.dims = dims;
        mInfo.type = ScalarType::U8;
    }
    const VolumeInfo& info() const override { return mInfo; }
    void read(void* dst, int64_t count) override {
        std::memset(dst, int(mSlicesRead % 251), size_t(count * mInfo.sliceSamples()));
        mSlicesRead += count;
    }
    std::string name() const override { return "counting"; }
    int64_t slicesRead() const { return mSlicesRead; }

private:
    VolumeInfo mInfo;
    std::atomic<int64_t> mSlicesRead{0};
};

TEST(StoreWriter, ReadsNoMoreThanOneLayerAhead) {
    // Memory is bounded by what has been read but not yet written: when layer k is done, at
    // most the slices of layer k+1 may have been read, whatever the volume's depth.
    test::ScratchDir dir;
    const int B = 4;
    CountingSource source({9, 9, 200});
    StoreWriteOptions o;
    o.brickSize = B;
    int64_t layer = 0;
    bool streamed = true;
    writeBrickStore(source, dir.file("s.vdiso"), o, [&](double) {
        const int64_t allowed = std::min<int64_t>((layer + 2) * B + 2, 200);
        if (source.slicesRead() > allowed) streamed = false;
        ++layer;
    });
    EXPECT_TRUE(streamed);
    EXPECT_EQ(source.slicesRead(), 200);
    EXPECT_EQ(layer, (200 - 1 + B - 1) / B);
}

}  // namespace
}  // namespace vdiso
