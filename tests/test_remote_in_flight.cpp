// Requests in flight over a network (io/remote/transfer_loop.h, core/extract/brick_prefetcher.h),
// against nginx behind the benches' link (tests/remote/link_proxy.cpp: a delay and a bandwidth
// cap): the window follows the link's delay and bandwidth, not a number of threads, and a
// remote view keeps its many requests in flight without a thread waiting on each.
#include <gtest/gtest.h>

#include <dirent.h>

#include <condition_variable>
#include <cstring>
#include <filesystem>
#include <mutex>
#include <string>
#include <vector>

#include "cache/brick_cache.h"
#include "io/remote/remote_file.h"
#include "io/store/brick_store.h"
#include "tests/loopback_servers.h"
#include "tests/test_util.h"

namespace vdiso {
namespace {

using test::LoopbackServer;

// Threads of this process now.
size_t threadsNow() {
    size_t n = 0;
    if (DIR* d = ::opendir("/proc/self/task")) {
        while (const dirent* e = ::readdir(d)) n += e->d_name[0] != '.';
        ::closedir(d);
    }
    return n;
}

class RemoteInFlight : public ::testing::Test {
protected:
    void SetUp() override {
        std::filesystem::create_directories(mDir.path() / "bkt");
        std::vector<unsigned char> bytes(size_t(8) << 20);
        for (size_t i = 0; i < bytes.size(); ++i) bytes[i] = static_cast<unsigned char>(i * 2654435761u >> 13);
        test::writeFile(mDir.file("bkt/blob"), bytes.data(), bytes.size());
        mBytes = std::move(bytes);
    }

    // What a session reading kRanges ranges of kRangeBytes at once through a link of `delayMs` and
    // `rateMbit` (0: none) wants in flight afterwards; the threads it added meanwhile, in `threads`.
    size_t wantedThrough(int delayMs, int rateMbit, size_t& threads) {
        LoopbackServer nginx = test::startNginx(mDir.file("bkt"), mDir.path().string(), mDir.file("nginx.log"));
        LoopbackServer link = test::startLinkProxy(nginx.port(), delayMs, rateMbit, mDir.file("link.log"));
        RemoteOptions options;
        options.connections = 256;
        RemoteFile file("http://127.0.0.1:" + std::to_string(link.port()) + "/blob", options, 4096);
        std::vector<unsigned char> out(kRanges * kRangeBytes);
        std::vector<ByteRange> ranges;
        for (size_t k = 0; k < kRanges; ++k) ranges.push_back({4096 + k * kRangeBytes, kRangeBytes, out.data() + k * kRangeBytes});
        // Every range sent at once, then waited for.
        std::mutex lock;
        std::condition_variable changed;
        size_t left = ranges.size(), failed = 0;
        const size_t before = threadsNow();
        for (const ByteRange& range : ranges)
            file.readCoveringAsync(range.offset, range.bytes, range.dst, {}, {}, nullptr, [&](std::exception_ptr e) {
                std::lock_guard hold(lock);
                failed += e != nullptr;
                if (--left == 0) changed.notify_one();
            });
        threads = threadsNow() - before;
        {
            std::unique_lock hold(lock);
            changed.wait(hold, [&] { return left == 0; });
        }
        EXPECT_EQ(failed, 0u);
        EXPECT_EQ(0, std::memcmp(out.data(), mBytes.data() + 4096, out.size()));
        return file.wantedInFlight(1, 100000);
    }

    static constexpr size_t kRanges = 96, kRangeBytes = 64 << 10;
    test::ScratchDir mDir;
    std::vector<unsigned char> mBytes;
};

// Twice the delay-bandwidth product in requests, plus two: 40 Mbit/s (5 MB/s) for 20 ms holds
// 1.5 ranges of 64 KB, for 100 ms 7.6; without a cap the link holds every range sent at once.
// (Measured here: 5, 12 and 77-87.) The bounds are loose (the loopback's own speed varies);
// their order is what is asserted.
TEST_F(RemoteInFlight, TheWindowFollowsTheLinksDelayAndBandwidth) {
    size_t threads = 0;
    const size_t shortDelay = wantedThrough(20, 40, threads);
    EXPECT_LE(threads, 1u) << kRanges << " ranges in flight";  // the session's transfer thread at most
    const size_t longDelay = wantedThrough(100, 40, threads);
    const size_t uncapped = wantedThrough(20, 0, threads);
    EXPECT_GE(shortDelay, 3u);
    EXPECT_LE(shortDelay, 10u);
    EXPECT_GT(longDelay, shortDelay + 3);
    EXPECT_LE(longDelay, 30u);
    EXPECT_GE(uncapped, 2 * longDelay) << "short delay " << shortDelay << ", long " << longDelay;
}

// A SAGE view of a store at a URL with small bricks (a few hundred requests, each held 30 ms),
// and a full extraction of a coarse level (--level): the process's threads stay at the
// strips', their decoding readers' and the transfer thread's, where a reader thread waited on
// each request in flight (32 a strip); the mesh is the local one.
TEST_F(RemoteInFlight, AViewKeepsItsRequestsInFlightWithoutAThreadEach) {
    test::CommandResult r =
        test::runVdiso("synth " + mDir.file("bkt/fine.vdiso") + " --kind head --size 128 --brick 8 --quiet");
    ASSERT_EQ(r.exitCode, 0) << r.output;
    LoopbackServer nginx = test::startNginx(mDir.file("bkt"), mDir.path().string(), mDir.file("nginx.log"));
    LoopbackServer link = test::startLinkProxy(nginx.port(), 30, 0, mDir.file("link.log"));
    const std::string view =
        std::string(VDISO_BINARY) + " extract --iso 600.5 --method sage --threads 2 --size 256x256 --force ";
    const std::string url = "http://127.0.0.1:" + std::to_string(link.port()) + "/fine.vdiso";
    // The whole surface, and a coarse level's by its own numbering (core/lod/level_source.h;
    // a full method's, on one thread, which reads ahead).
    for (const std::string level : {"", "--level 1 --method octree --threads 1 "}) {
        SCOPED_TRACE(level);
        // The most threads seen, sampled every 2 ms while the view runs.
        r = test::runCommand("bash -c '" + view + level + "--stats " + mDir.file("remote.json") + " -o " +
                             mDir.file("remote.ply") + " " + url +
                             " & pid=$!; most=0; while kill -0 $pid 2>/dev/null; do "
                             "n=$(ls /proc/$pid/task 2>/dev/null | wc -l); [ $n -gt $most ] && most=$n; sleep 0.002; done; "
                             "wait $pid || exit 1; echo MOST $most'");
        ASSERT_EQ(r.exitCode, 0) << r.output;
        const size_t at = r.output.find("MOST ");
        ASSERT_NE(at, std::string::npos) << r.output;
        const int most = std::stoi(r.output.substr(at + 5));
        // Main, 1 more strip, 2 readers a strip, the transfer thread, the index's background
        // reader, TBB's and the output's few.
        EXPECT_LE(most, 14) << r.output;
        EXPECT_GE(most, 3) << r.output;  // the sampling saw the view run
        const std::string stats = test::readText(mDir.file("remote.json"));
        const size_t requests = std::stoul(stats.substr(stats.find("\"remote_requests\": ") + 19));
        EXPECT_GE(requests, level.empty() ? 100u : 20u) << stats;

        r = test::runCommand(view + level + "-o " + mDir.file("local.ply") + " " + mDir.file("bkt/fine.vdiso"));
        ASSERT_EQ(r.exitCode, 0) << r.output;
        EXPECT_EQ(test::readFile(mDir.file("remote.ply")), test::readFile(mDir.file("local.ply")));
    }
}

// The cache's background loads (BrickCache::startAcquire) from a store at a URL: bricks held
// already are left out (an empty handle), the others read in one request per run of them lying
// one after another in the file, the samples those of the local file; a load of held bricks only
// is none.
TEST_F(RemoteInFlight, ABackgroundLoadLeavesOutWhatIsHeld) {
    test::CommandResult r = test::runVdiso("synth " + mDir.file("bkt/head.vdiso") + " --kind head --size 96 --quiet");
    ASSERT_EQ(r.exitCode, 0) << r.output;
    LoopbackServer nginx = test::startNginx(mDir.file("bkt"), mDir.path().string(), mDir.file("nginx.log"));
    StoreOpenOptions options;
    BrickStoreReader remote("http://127.0.0.1:" + std::to_string(nginx.port()) + "/head.vdiso", options);
    BrickStoreReader local(mDir.file("bkt/head.vdiso"));
    BrickCache cache(remote, uint64_t(64) << 20);
    ASSERT_TRUE(cache.loadsInBackground());
    // Three x-neighbours, one after another in the file.
    const std::vector<int64_t> ids = {0, 1, 2};
    ASSERT_TRUE(remote.readsTogether(0, 1) && remote.readsTogether(1, 2));
    BrickHandle held = cache.acquire(1);
    const uint64_t before = remote.remote()->requests();

    std::mutex lock;
    std::condition_variable changed;
    bool arrived = false;
    auto signal = [&] {
        std::lock_guard hold(lock);
        arrived = true;
        changed.notify_one();
    };
    std::unique_ptr<BrickLoad> load = cache.startAcquire(ids, signal, nullptr);
    ASSERT_TRUE(load);
    {
        std::unique_lock hold(lock);
        changed.wait(hold, [&] { return arrived; });
    }
    std::vector<BrickHandle> handles = cache.finishAcquire(*load);
    ASSERT_EQ(handles.size(), 3u);
    EXPECT_EQ(handles[1].samples(), nullptr);
    EXPECT_EQ(remote.remote()->requests() - before, 2u);  // bricks 0 and 2 lie apart now
    std::vector<unsigned char> expected(remote.brickBytes());
    for (const size_t k : {size_t(0), size_t(2)}) {
        ASSERT_NE(handles[k].samples(), nullptr);
        local.readBrick(ids[k], expected.data());
        EXPECT_EQ(std::memcmp(handles[k].samples(), expected.data(), expected.size()), 0) << "brick " << ids[k];
    }
    EXPECT_EQ(cache.loadsInFlight(), 0u);
    EXPECT_FALSE(cache.startAcquire(ids, signal, nullptr));  // all held now
}

}  // namespace
}  // namespace vdiso
