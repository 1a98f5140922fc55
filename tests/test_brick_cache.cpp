// The brick cache: budget never exceeded, least recently used evicted first, pinned bricks
// kept, corrupt bricks reported and not cached.
#include <gtest/gtest.h>

#include <cstring>
#include <fstream>

#include <sys/resource.h>

#include "cache/brick_cache.h"
#include "io/error.h"
#include "io/readers/volume_open.h"
#include "io/store/store_writer.h"
#include "tests/test_util.h"

namespace vdiso {
namespace {

class BrickCacheTest : public ::testing::Test {
protected:
    void SetUp() override {
        test::MemoryVolume volume({33, 17, 9}, ScalarType::U16);  // 4 x 2 x 1 bricks of 8
        StoreWriteOptions o;
        o.brickSize = 8;
        path = dir.file("c.vdiso");
        writeBrickStore(volume, path, o);
    }
    test::ScratchDir dir;
    std::string path;
};

TEST_F(BrickCacheTest, EvictsLeastRecentlyUsedWithinBudget) {
    const BrickStoreReader store(path);
    BrickCache cache(store, 3 * store.brickBytes());
    for (int64_t id : {0, 1, 2}) cache.acquire(id);  // released at once
    cache.acquire(0);                                  // 0 is now the most recent
    cache.acquire(3);                                  // evicts 1, the least recent
    EXPECT_EQ(cache.counters().evictions, 1u);
    const uint64_t missesBefore = cache.counters().misses;
    cache.acquire(0);
    cache.acquire(2);
    EXPECT_EQ(cache.counters().misses, missesBefore);  // 0 and 2 stayed
    cache.acquire(1);
    EXPECT_EQ(cache.counters().misses, missesBefore + 1);  // 1 was the one evicted
    EXPECT_LE(cache.residentBytes(), cache.budgetBytes());
}

TEST_F(BrickCacheTest, PinnedBricksAreNeverEvictedAndTheBudgetHolds) {
    const BrickStoreReader store(path);
    BrickCache cache(store, 2 * store.brickBytes());
    BrickHandle a = cache.acquire(0), b = cache.acquire(1);
    EXPECT_THROW(cache.acquire(2), std::runtime_error);  // both slots pinned
    b.release();
    BrickHandle c = cache.acquire(2);
    EXPECT_EQ(c.samples() != nullptr, true);
    EXPECT_LE(cache.residentBytes(), cache.budgetBytes());
    EXPECT_THROW(BrickCache(store, store.brickBytes()), std::invalid_argument);
}

TEST_F(BrickCacheTest, SamplesMatchTheReaderAndCountersAddUp) {
    const BrickStoreReader store(path);
    BrickCache cache(store, 64u << 20);
    std::vector<unsigned char> expected(store.brickBytes());
    for (int round = 0; round < 2; ++round)
        for (int64_t id = 0; id < int64_t(store.index().size()); ++id) {  // every level's
            store.readBrick(id, expected.data());
            const BrickHandle h = cache.acquire(id);
            EXPECT_EQ(std::memcmp(h.samples(), expected.data(), expected.size()), 0);
        }
    const CacheCounters c = cache.counters();
    EXPECT_EQ(c.requests, uint64_t(2 * store.index().size()));
    EXPECT_EQ(c.misses, uint64_t(store.index().size()));
    EXPECT_EQ(c.hits, c.misses);
    EXPECT_EQ(c.bytesRead, store.header().storedBrickBytes);
}

TEST_F(BrickCacheTest, CorruptBrickIsReportedNotReturned) {
    auto bytes = test::readFile(path);
    const uint64_t offset = BrickStoreReader(path).index()[2].offset;
    bytes[offset + 10] ^= 0xff;
    test::writeFile(path, bytes.data(), bytes.size());
    const BrickStoreReader store(path);
    BrickCache cache(store, 8 * store.brickBytes());
    try {
        cache.acquire(2);
        FAIL() << "corrupt brick returned";
    } catch (const IoError& e) {
        EXPECT_NE(std::string(e.what()).find("brick 2"), std::string::npos) << e.what();
    }
    EXPECT_THROW(cache.acquire(2), IoError);  // not cached as if good
    EXPECT_NO_THROW(cache.acquire(1));
}


TEST_F(BrickCacheTest, ColdReadsReturnTheSameBricksFromDisk) {
    const BrickStoreReader buffered(path);
    const BrickStoreReader cold(path, ReadMode::Cold);
    EXPECT_STREQ(buffered.readMethod(), "buffered");
    // ext4 and most disk file systems take O_DIRECT; tmpfs does not, and then pages are
    // dropped after each read instead. Either way the method is reported, never hidden.
    EXPECT_TRUE(std::string(cold.readMethod()) == "direct" ||
                std::string(cold.readMethod()) == "fadvise")
        << cold.readMethod();
    std::vector<unsigned char> a(buffered.brickBytes()), b(cold.brickBytes());
    for (int64_t id = 0; id < int64_t(buffered.index().size()); ++id) {
        buffered.readBrick(id, a.data());
        cold.readBrick(id, b.data());
        EXPECT_EQ(a, b) << "brick " << id;
    }
    BrickCache cache(cold, 64u << 20);
    for (int64_t id = 0; id < int64_t(cold.index().size()); ++id) cache.acquire(id);
    EXPECT_EQ(cache.counters().bytesRead, cold.header().storedBrickBytes);
}

TEST_F(BrickCacheTest, ColdReadOfATruncatedStoreFailsAtOpen) {
    auto bytes = test::readFile(path);
    bytes.resize(bytes.size() - 100);
    test::writeFile(path, bytes.data(), bytes.size());
    EXPECT_THROW(BrickStoreReader(path, ReadMode::Cold), IoError);
}

// Memory the cache cannot get is said in words, naming the store and the budget (it was a bare
// std::bad_alloc). The address space is limited to what the process holds once the cache has
// its first chunk, so the next chunk's mapping fails.
TEST(BrickCache, MemoryItCannotGetIsSaidWithTheStore) {
    if (VDISO_UNDER_ASAN) GTEST_SKIP() << "an address-space limit and AddressSanitizer exclude each other";
    test::ScratchDir dir;
    SynthParams p;
    p.dims = {256, 256, 256};
    writeBrickStore(*openSynthVolume(p), dir.file("h.vdiso"), StoreWriteOptions{});
    const BrickStoreReader store(dir.file("h.vdiso"));
    BrickCache cache(store, uint64_t(1) << 30);
    cache.acquire(0).release();  // the first chunk: about 390 bricks' room
    auto vmBytes = [] {
        std::ifstream status("/proc/self/status");
        for (std::string line; std::getline(status, line);)
            if (line.rfind("VmSize:", 0) == 0) return uint64_t(std::stoull(line.substr(7))) << 10;
        return uint64_t(0);
    };
    rlimit old{};
    ::getrlimit(RLIMIT_AS, &old);
    rlimit limited = old;
    limited.rlim_cur = vmBytes() + (uint64_t(8) << 20);
    ASSERT_EQ(::setrlimit(RLIMIT_AS, &limited), 0);
    std::string message;
    try {
        for (int64_t id = 1; id < store.layout().brickCount(); ++id) cache.acquire(id).release();
    } catch (const IoError& e) {
        message = e.what();
    } catch (const std::exception& e) {
        message = std::string("not an IoError: ") + e.what();
    }
    ::setrlimit(RLIMIT_AS, &old);
    EXPECT_EQ(message.rfind(dir.file("h.vdiso") + ": the brick cache cannot get", 0), 0u) << message;
    // The library names the quantity; the front end adds its option (cli/args.h messageOf).
    EXPECT_NE(message.find("lower the budget"), std::string::npos) << message;
    EXPECT_EQ(message.find("--"), std::string::npos) << message;
}

}  // namespace
}  // namespace vdiso
