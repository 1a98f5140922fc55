// vdiso serve under clients that flood it: a viewer's share of the workers is bounded whatever
// it sends (serve/frame_pool.h), a client that does not read gives up its passes, a stuck client
// is dropped at the write timeout however many there are, and a connection flooding bad
// messages costs about what the README says.
#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdio>
#include <fstream>
#include <future>
#include <thread>
#include <vector>

#include <sys/socket.h>
#include <unistd.h>

#include "core/view_presets.h"
#include "serve/outbox.h"
#include "tests/serve_test_util.h"

namespace vdiso::serve {
namespace {

using test::maskedFrame;
using test::presetFor;
using test::ServerFixture;
using test::unreadingClient;
using test::viewOf;
using Clock = std::chrono::steady_clock;

// A client sending VIEWs without end (every `gap`, each another camera and isovalue, so each
// frame's chunks are new), reading what comes back or not; stops when told or dropped.
class Flooder {
public:
    Flooder(const ServerFixture& fixture, bool reads, int id) : mFd(unreadingClient(fixture, !reads)) {
        if (mFd < 0) return;
        if (reads)
            mReader = std::thread([this] {
                char buffer[65536];
                while (!mStop && recv(mFd, buffer, sizeof buffer, 0) > 0) {
                }
            });
        // The cameras made first: the flood costs the client nothing.
        std::vector<Camera> cameras;
        for (int k = 0; k < 16; ++k) cameras.push_back(presetFor(fixture.storePath, ViewPreset::Closeup, 1024, 22.5 * k + 40 * id));
        mWriter = std::thread([this, cameras] {
            for (uint32_t seq = 1; !mStop; ++seq) {
                const std::string view =
                    maskedFrame(0x2, encodeView(viewOf(cameras[seq % 16], seq, kHeadSkinIso + 0.5 * (seq % 16))));
                if (send(mFd, view.data(), view.size(), MSG_NOSIGNAL | MSG_DONTWAIT) < 0 && errno != EAGAIN) break;
                std::this_thread::sleep_for(std::chrono::milliseconds(2));
            }
        });
    }
    ~Flooder() {
        mStop = true;
        if (mFd >= 0) shutdown(mFd, SHUT_RDWR);
        if (mWriter.joinable()) mWriter.join();
        if (mReader.joinable()) mReader.join();
        if (mFd >= 0) close(mFd);
    }
    bool connected() const { return mFd >= 0; }

private:
    int mFd;
    std::atomic<bool> mStop{false};
    std::thread mWriter, mReader;
};

// Ordinary viewers, each turning its camera a step a frame, one frame at a time.
class OrdinaryViewers {
public:
    OrdinaryViewers(ServerFixture& fixture, int viewers) : mCameras(static_cast<size_t>(viewers)) {
        for (int k = 0; k < viewers; ++k) {
            mClients.push_back(fixture.client());
            for (int step = 0; step < 36; ++step)
                mCameras[size_t(k)].push_back(presetFor(fixture.storePath, ViewPreset::Normal, 256, 10.0 * step + 90 * k));
        }
        mSeq.assign(size_t(viewers), 0);
    }
    // Frames for `window`: the seconds each took (from its VIEW to its final frameEnd), all
    // viewers together. A viewer whose frame has not come 5 s after the window is interrupted
    // (starved: it counts no frame, then or later).
    std::vector<double> frames(std::chrono::milliseconds window) {
        const Clock::time_point until = Clock::now() + window;
        std::vector<std::future<std::vector<double>>> runs;
        for (size_t k = 0; k < mClients.size(); ++k)
            runs.push_back(std::async(std::launch::async, [this, k, until] {
                std::vector<double> seconds;
                try {
                    while (Clock::now() < until) {
                        const uint32_t seq = ++mSeq[k];
                        const ClientFrame f = mClients[k]->requestFrame(viewOf(mCameras[k][seq % 36], seq));
                        if (f.status == "complete") seconds.push_back(f.completeSeconds);
                    }
                } catch (const std::exception&) {  // interrupted
                }
                return seconds;
            }));
        for (auto& r : runs)
            if (r.wait_until(until + std::chrono::seconds(5)) != std::future_status::ready)
                for (auto& c : mClients) c->interrupt();
        std::vector<double> all;
        for (auto& r : runs) {
            const std::vector<double> s = r.get();
            all.insert(all.end(), s.begin(), s.end());
        }
        return all;
    }

private:
    std::vector<std::unique_ptr<ViewerClient>> mClients;
    std::vector<std::vector<Camera>> mCameras;
    std::vector<uint32_t> mSeq;
};

double median(std::vector<double> v) {
    if (v.empty()) return INFINITY;
    std::nth_element(v.begin(), v.begin() + ptrdiff_t(v.size() / 2), v.end());
    return v[v.size() / 2];
}

// 4 clients flooding VIEWs (2 reading their frames, 2 not) and 4 ordinary viewers: the ordinary
// viewers keep getting frames, at about their time alone (with first passes always ahead, and a
// pass a flooder's VIEW, they used to get none in a minute).
TEST(ServeFairness, FloodingClientsDoNotStarveOrdinaryViewers) {
    ServerFixture fixture(uint64_t(256) << 20, 1, {160, 160, 160});
    OrdinaryViewers viewers(fixture, 4);
    // Windows alone and among flooders in turn, so that whatever else loads the machine weighs
    // on both alike.
    const auto window = std::chrono::milliseconds(1500);
    std::vector<double> alone, flooded;
    for (int round = 0; round < 3; ++round) {
        const std::vector<double> a = viewers.frames(window);
        alone.insert(alone.end(), a.begin(), a.end());
        std::vector<std::unique_ptr<Flooder>> flooders;
        for (int k = 0; k < 4; ++k) {
            flooders.push_back(std::make_unique<Flooder>(fixture, k % 2 == 0, k));
            ASSERT_TRUE(flooders.back()->connected());
        }
        std::this_thread::sleep_for(std::chrono::milliseconds(300));  // the flood under way
        const std::vector<double> f = viewers.frames(window);
        flooded.insert(flooded.end(), f.begin(), f.end());
    }
    ASSERT_GE(alone.size(), 8u);
    std::printf("ordinary viewers' median frame: %.3f s alone (%zu frames), %.3f s among flooders (%zu frames)\n",
                median(alone), alone.size(), median(flooded), flooded.size());
    // Starved, they got no frame at all. The 2x holds here on a quiet machine (1.0-1.5x,
    // bench/log.md); CI runs other tests beside this one, and a fresh clone's run once reached
    // 2.3x with a compile beside it, so the assertion leaves room for that load: a third of the
    // frames they make alone, and at most 3x their median frame.
    EXPECT_GE(3 * flooded.size(), alone.size()) << "ordinary viewers starved";
    // Under ASan a flooder's pass, which a viewer may wait for, takes ten times as long as in a
    // build that is measured (1.6-1.8x there): only the starvation is checked.
    if (!VDISO_UNDER_ASAN) {
        EXPECT_LE(median(flooded), 3.0 * median(alone))
            << "median frame " << median(flooded) << " s among flooders, " << median(alone) << " s alone ("
            << flooded.size() << " and " << alone.size() << " frames)";
    }
}

// 4 clients that never read, each sending VIEWs whose frames outgrow the socket buffers: every
// one is dropped within the write timeout of its socket filling (a few frames, seconds at most),
// not tens of seconds later; an ordinary viewer is served meanwhile.
TEST(ServeFairness, EveryStuckClientIsDroppedAtTheBound) {
    const double timeout = 2.0;
    ServerFixture fixture(uint64_t(256) << 20, 1, {160, 160, 160}, 0, timeout);
    std::vector<std::unique_ptr<Flooder>> stuck;
    const Clock::time_point start = Clock::now();
    for (int k = 0; k < 4; ++k) stuck.push_back(std::make_unique<Flooder>(fixture, false, k));
    auto other = fixture.client();
    EXPECT_EQ(other->requestFrame(viewOf(presetFor(fixture.storePath, ViewPreset::Normal, 160), 1)).status, "complete");
    while (fixture.server->counters().viewersDropped < 4 && Clock::now() - start < std::chrono::seconds(60))
        std::this_thread::sleep_for(std::chrono::milliseconds(20));
    const double seconds = std::chrono::duration<double>(Clock::now() - start).count();
    std::printf("4 stuck clients dropped %.2f s after they connected (write timeout %.0f s)\n", seconds, timeout);
    EXPECT_EQ(fixture.server->counters().viewersDropped, 4u);
    // Runs alone (tests/CMakeLists.txt: RUN_SERIAL): beside the flooding test on 2 cores it once
    // took 11.3 s. Under ASan the frames that fill the sockets take ten times as long: there,
    // only that all go.
    if (!VDISO_UNDER_ASAN) {
        EXPECT_LT(seconds, timeout + 8.0) << "the last stuck client was dropped after " << seconds << " s";
    }
    stuck.clear();
    EXPECT_EQ(other->requestFrame(viewOf(presetFor(fixture.storePath, ViewPreset::Normal, 160, 20), 2)).status, "complete");
}

size_t residentBytes() {
    std::ifstream status("/proc/self/status");
    std::string line;
    while (std::getline(status, line))
        if (line.rfind("VmRSS:", 0) == 0) return size_t(std::stoull(line.substr(6))) << 10;
    return 0;
}

// A connection writing small bad messages as fast as it can and reading none of the replies:
// the server stops reading it once Outbox::kControlLimit of replies wait, so it costs the
// server about that, not the outbox's 32 MB limit (twice over, counted without overhead).
TEST(ServeFairness, AFloodOfBadMessagesCostsAboutTheControlLimit) {
    if (VDISO_UNDER_ASAN) GTEST_SKIP() << "ASan's quarantine keeps freed memory resident: the growth means nothing there";
    ServerFixture fixture(uint64_t(256) << 20, 1, {72, 72, 72}, 0, 30.0);
    const int fd = unreadingClient(fixture);
    ASSERT_GE(fd, 0);
    std::string burst;
    for (int k = 0; k < 64; ++k) burst += maskedFrame(0x2, {42, 1, 0, 0, 0, 0, 0, 0});
    const size_t before = residentBytes();
    uint64_t sent = 0;
    for (const Clock::time_point until = Clock::now() + std::chrono::seconds(3); Clock::now() < until;) {
        const ssize_t n = send(fd, burst.data(), burst.size(), MSG_NOSIGNAL | MSG_DONTWAIT);
        if (n > 0) sent += uint64_t(n);
        else std::this_thread::sleep_for(std::chrono::milliseconds(1));
    }
    const size_t grown = residentBytes() - std::min(before, residentBytes());
    std::printf("a flood of %llu bytes of bad messages grew the server by %.1f MB\n", (unsigned long long)sent,
                double(grown) / double(1 << 20));
    EXPECT_GT(sent, uint64_t(1) << 16);
    EXPECT_LT(grown, size_t(12) << 20) << "the flood cost " << (grown >> 20) << " MB";
    close(fd);
}

}  // namespace
}  // namespace vdiso::serve
