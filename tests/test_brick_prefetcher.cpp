// The prefetcher's reader threads (core/extract/brick_prefetcher.h): bricks the source reads
// together (neighbours in a store's file) are gathered from the next items into one read.
#include <gtest/gtest.h>

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
        return mInner.acquire(id);
    }
    bool readsWithNext(int64_t id) const override { return id % 4 != 3; }
    std::vector<BrickHandle> acquireRun(int64_t first, int count) override {
        record("run " + std::to_string(first) + "+" + std::to_string(count));
        std::vector<BrickHandle> handles;
        for (int k = 0; k < count; ++k) handles.push_back(mInner.acquire(first + k));
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
};

TEST(BrickPrefetcher, ReadsNeighboursInTheFileTogether) {
    test::MemoryBrickSource memory({129, 9, 9}, ScalarType::U16, 8, [](int64_t x, int64_t, int64_t) { return double(x); });
    RowSource source(memory);
    {
        BrickPrefetcher prefetcher(source, 16, 1);
        // Item 0 is the extraction's own. Then 5 gathers 4, 6 and 7 (7 does not read with 8);
        // 9 gathers 8 and 10 but not 12, which is item 5's alone; 2 stands alone.
        for (const int64_t id : {0, 5, 4, 9, 6, 7, 8, 12, 10, 2}) prefetcher.push(id);
        prefetcher.close();
        for (int k = 0; k < 200 && source.reads().size() < 4; ++k) std::this_thread::sleep_for(std::chrono::milliseconds(5));
        prefetcher.consumed(10);
    }
    EXPECT_EQ(source.reads(), (std::vector<std::string>{"run 4+4", "run 8+3", "brick 12", "brick 2"}));
    EXPECT_EQ(memory.pinned(), 0);
}

}  // namespace
}  // namespace vdiso
