// The prefetcher's reader threads (core/extract/brick_prefetcher.h): bricks the source reads
// together (neighbours in a store's file) are gathered from the next items into one read.
#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <cstdlib>
#include <chrono>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "core/extract/brick_prefetcher.h"
#include "tests/extract_test_util.h"

namespace vdiso {
namespace {

// Bricks in rows of 4 that read with their successor within a row; records each read.
class RowSource final : public BrickSource {
public:
    explicit RowSource(BrickSource& inner) : mInner(inner) {}
    const VolumeInfo& volume() const override { return mInner.volume(); }
    const BrickLayout& layout() const override { return mInner.layout(); }
    std::span<const BrickRange> brickRanges() const override { return mInner.brickRanges(); }
    BrickHandle acquire(int64_t id) override {
        record("brick " + std::to_string(id));
        if (id == mHeld)  // the reader waits here until the test has pushed what it gathers from
            while (!mRelease) std::this_thread::sleep_for(std::chrono::milliseconds(1));
        return mInner.acquire(id);
    }
    // Reading brick `id` waits until release(): the items pushed meanwhile are all there when
    // the reader gathers its next run, however the threads are scheduled.
    void hold(int64_t id) { mHeld = id; }
    void releaseHeld() { mRelease = true; }
    bool readsTogether(int64_t a, int64_t b) const override { return std::abs(a - b) == 1 && std::min(a, b) % 4 != 3; }
    std::vector<BrickHandle> acquireTogether(std::span<const int64_t> ids) override {
        std::string what = "run";
        for (const int64_t id : ids) what += " " + std::to_string(id);
        record(what);
        std::vector<BrickHandle> handles;
        for (const int64_t id : ids) handles.push_back(mInner.acquire(id));
        return handles;
    }
    std::vector<std::string> reads() const {
        std::lock_guard lock(mMutex);
        return mReads;
    }

protected:
    void release(int64_t) override {}

private:
    void record(const std::string& what) {
        std::lock_guard lock(mMutex);
        mReads.push_back(what);
    }
    BrickSource& mInner;
    mutable std::mutex mMutex;
    std::vector<std::string> mReads;
    std::atomic<int64_t> mHeld{-1};
    std::atomic<bool> mRelease{false};
};

TEST(BrickPrefetcher, ReadsNeighboursInTheFileTogether) {
    // 16 bricks in a row: 128 cells of 8 along x.
    test::MemoryBrickSource memory({129, 9, 9}, ScalarType::U16, 8, [](int64_t x, int64_t, int64_t) { return double(x); });
    RowSource source(memory);
    {
        BrickPrefetcher prefetcher(source, 16, 1);
        // Item 0 is the extraction's own; item 1 (brick 15, last of its row: no neighbour) holds the reader
        // until every item is pushed. Then 5 gathers 4, 6 and 7 (7 does not read with 8); 9
        // gathers 8 and 10 but not 12, which is item 6's alone; 2 stands alone.
        source.hold(15);
        for (const int64_t id : {0, 15, 5, 4, 9, 6, 7, 8, 12, 10, 2}) prefetcher.push(id);
        prefetcher.close();
        source.releaseHeld();
        for (int k = 0; k < 200 && source.reads().size() < 5; ++k) std::this_thread::sleep_for(std::chrono::milliseconds(5));
        prefetcher.consumed(11);
    }
    EXPECT_EQ(source.reads(), (std::vector<std::string>{"brick 15", "run 5 4 6 7", "run 9 8 10", "brick 12", "brick 2"}));
    EXPECT_EQ(memory.pinned(), 0);
}

// Bricks found ahead but not yet known to show (offered) are read with a run they join, and
// left in the source unpinned; those that join nothing are not read.
TEST(BrickPrefetcher, ReadsOfferedNeighboursWithTheirRun) {
    test::MemoryBrickSource memory({129, 9, 9}, ScalarType::U16, 8, [](int64_t x, int64_t, int64_t) { return double(x); });
    RowSource source(memory);
    size_t offeredLoaded = 0;
    {
        BrickPrefetcher prefetcher(source, 16, 1);
        prefetcher.push(0);  // the extraction's own
        prefetcher.push(5);
        prefetcher.offer({4, 6, 12});
        prefetcher.close();
        for (int k = 0; k < 200 && source.reads().empty(); ++k) std::this_thread::sleep_for(std::chrono::milliseconds(5));
        for (int k = 0; k < 200 && prefetcher.offeredLoaded() < 2; ++k) std::this_thread::sleep_for(std::chrono::milliseconds(5));
        offeredLoaded = prefetcher.offeredLoaded();
        prefetcher.consumed(2);
    }
    EXPECT_EQ(source.reads(), (std::vector<std::string>{"run 5 4 6"}));
    EXPECT_EQ(offeredLoaded, 2u);
    EXPECT_EQ(memory.pinned(), 0);
}

}  // namespace
}  // namespace vdiso
