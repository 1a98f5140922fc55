// The remote disk cache's own thread (io/remote/disk_cache.h): what write() takes is on disk
// once the cache is gone, for the next process; a range beyond the bound of what may wait is not
// kept, and that is only a miss; a process forked while the thread waits can drop the cache;
// temporaries of writers that ended mid-write go.
#include <gtest/gtest.h>

#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdint>
#include <filesystem>
#include <string>
#include <memory>
#include <thread>
#include <vector>

#include "io/remote/disk_cache.h"
#include "test_util.h"

namespace vdiso {
namespace {

std::vector<unsigned char> rangeBytes(uint64_t offset, size_t n) {
    std::vector<unsigned char> bytes(n);
    for (size_t i = 0; i < n; ++i) bytes[i] = static_cast<unsigned char>((offset + i) * 2654435761u >> 13);
    return bytes;
}

TEST(DiskCache, WhatWasWrittenIsKeptForTheNextProcessOnceTheCacheIsGone) {
    test::ScratchDir dir;
    const std::string root = dir.file("cache");
    constexpr int kRanges = 200;
    constexpr size_t kBytes = 20000;
    {
        const RangeDiskCache cache(root, "s3://bucket/key", "etag-1", uint64_t(1) << 30);
        for (int k = 0; k < kRanges; ++k) {
            const std::vector<unsigned char> bytes = rangeBytes(uint64_t(k) * kBytes, kBytes);
            cache.write(uint64_t(k) * kBytes, kBytes, bytes.data());
        }
    }  // the writes waiting are made here
    const RangeDiskCache next(root, "s3://bucket/key", "etag-1", uint64_t(1) << 30);
    std::vector<unsigned char> got(kBytes);
    for (int k = 0; k < kRanges; ++k) {
        ASSERT_TRUE(next.read(uint64_t(k) * kBytes, kBytes, got.data())) << "range " << k;
        EXPECT_EQ(got, rangeBytes(uint64_t(k) * kBytes, kBytes)) << "range " << k;
    }
    EXPECT_EQ(next.hits(), uint64_t(kRanges));
    // Another version of the object: none of it.
    const RangeDiskCache changed(root, "s3://bucket/key", "etag-2", uint64_t(1) << 30);
    EXPECT_FALSE(changed.read(0, kBytes, got.data()));
}

TEST(DiskCache, ARangeBeyondWhatMayWaitIsNotKept) {
    test::ScratchDir dir;
    const std::string root = dir.file("cache");
    const size_t n = RangeDiskCache::kPendingBytes + 1;
    {
        const RangeDiskCache cache(root, "https://host/volume.vdiso", "v", uint64_t(1) << 32);
        const std::vector<unsigned char> bytes = rangeBytes(0, n);
        cache.write(0, n, bytes.data());
        const std::vector<unsigned char> small = rangeBytes(n, 100);
        cache.write(n, 100, small.data());
    }
    const RangeDiskCache next(root, "https://host/volume.vdiso", "v", uint64_t(1) << 32);
    std::vector<unsigned char> got(n);
    EXPECT_FALSE(next.read(0, n, got.data()));
    EXPECT_TRUE(next.read(n, 100, got.data()));
    EXPECT_EQ(std::vector<unsigned char>(got.begin(), got.begin() + 100), rangeBytes(n, 100));
}

// A temporary left by a process that ended mid-write is removed when a cache opens, once it is
// an hour old; a younger one (a write going on) stays.
TEST(DiskCache, TemporariesLeftByAnEndedWriterGoWhenACacheOpens) {
    test::ScratchDir dir;
    const std::filesystem::path folder = dir.path() / "cache" / "someobject";
    std::filesystem::create_directories(folder);
    const std::filesystem::path old = folder / ".tmp-4242-0", young = folder / ".tmp-4242-1";
    test::writeFile(old.string(), std::string(5000, 'x'));
    test::writeFile(young.string(), std::string(5000, 'y'));
    std::filesystem::last_write_time(old, std::filesystem::file_time_type::clock::now() - std::chrono::hours(2));
    const RangeDiskCache cache(dir.file("cache"), "s3://bucket/key", "v", uint64_t(1) << 30);
    EXPECT_FALSE(std::filesystem::exists(old));
    EXPECT_TRUE(std::filesystem::exists(young));
}

// Python's multiprocessing forks with stores open: the child inherits the cache, with its
// writer thread waiting (on a condition variable whose waiter the child never has), and must be
// able to drop it and end. The child here ends by itself within seconds or the test fails.
TEST(DiskCache, AProcessForkedWhileItsThreadWaitsDropsTheCacheAndEnds) {
    test::ScratchDir dir;
    auto cache = std::make_unique<RangeDiskCache>(dir.file("cache"), "s3://bucket/key", "v", uint64_t(1) << 30);
    const std::vector<unsigned char> bytes = rangeBytes(0, 1000);
    cache->write(0, bytes.size(), bytes.data());
    std::this_thread::sleep_for(std::chrono::milliseconds(50));  // written: the thread waits again
    const pid_t child = ::fork();
    ASSERT_GE(child, 0);
    if (child == 0) {
        cache->write(1000, bytes.size(), bytes.data());  // not kept, and no thread started
        cache.reset();
        ::_exit(0);
    }
    int status = 0;
    bool ended = false;
    for (int k = 0; k < 100 && !ended; ++k) {
        ended = ::waitpid(child, &status, WNOHANG) == child;
        if (!ended) std::this_thread::sleep_for(std::chrono::milliseconds(50));
    }
    if (!ended) {
        ::kill(child, SIGKILL);
        ::waitpid(child, &status, 0);
    }
    ASSERT_TRUE(ended) << "the forked child hung dropping the disk cache";
    EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0);
    cache.reset();
    const RangeDiskCache next(dir.file("cache"), "s3://bucket/key", "v", uint64_t(1) << 30);
    std::vector<unsigned char> got(bytes.size());
    EXPECT_TRUE(next.read(0, got.size(), got.data()));
    EXPECT_FALSE(next.read(1000, got.size(), got.data()));
}

}  // namespace
}  // namespace vdiso
