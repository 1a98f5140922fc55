// The frame pool of vdiso serve (serve/frame_pool.h): a fixed number of workers run every
// task's passes; first passes before later ones, each kind in turn; a task posted while it runs
// runs again after; a removed task does not run.
#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <functional>
#include <mutex>
#include <thread>
#include <vector>

#include "serve/frame_pool.h"

namespace vdiso::serve {
namespace {

struct Recorded final : FramePool::Task {
    int id;
    std::mutex& mutex;
    std::vector<int>& order;
    std::function<void()> during;
    Recorded(int i, std::mutex& m, std::vector<int>& o) : id(i), mutex(m), order(o) {}
    void runPass() override {
        {
            std::lock_guard lock(mutex);
            order.push_back(id);
        }
        if (during) during();
    }
};

// A task that holds the pool's one worker until released.
struct Blocker final : FramePool::Task {
    std::atomic<bool> running{false}, release{false};
    void runPass() override {
        running = true;
        while (!release) std::this_thread::sleep_for(std::chrono::milliseconds(1));
        running = false;
    }
};

TEST(FramePool, FirstPassesGoFirstThenEachInTurn) {
    FramePool pool(1);
    Blocker blocker;
    pool.post(blocker, false);
    while (!blocker.running) std::this_thread::yield();
    std::mutex mutex;
    std::vector<int> order;
    std::vector<std::unique_ptr<Recorded>> tasks;
    for (int k = 0; k < 4; ++k) tasks.push_back(std::make_unique<Recorded>(k, mutex, order));
    // Later passes of 0 and 1 come first, then first passes of 2 and 3; 0 posts a first pass
    // too, which moves it ahead of 1 (behind 2 and 3, which came before).
    pool.post(*tasks[0], false);
    pool.post(*tasks[1], false);
    pool.post(*tasks[2], true);
    pool.post(*tasks[3], true);
    pool.post(*tasks[0], true);
    EXPECT_EQ(pool.waiting(), 4u);
    blocker.release = true;
    for (auto& t : tasks) {
        while (!pool.idle(*t)) std::this_thread::yield();
    }
    EXPECT_EQ(order, (std::vector<int>{2, 3, 0, 1}));
    EXPECT_EQ(pool.passes(), 5u);
}

TEST(FramePool, ATaskPostedWhileItRunsRunsAgainBehindTheOthers) {
    FramePool pool(1);
    std::mutex mutex;
    std::vector<int> order;
    Recorded heavy(0, mutex, order), light(1, mutex, order);
    int heavyPasses = 0;
    // The light task is posted before the heavy one's first pass posts its second (the worker
    // may start that pass before the test posts the light task: it once ran 0, 0, 1, ...).
    std::atomic<bool> lightPosted{false};
    // The heavy task always has another pass due; the light one posts one pass at a time.
    heavy.during = [&] {
        while (!lightPosted) std::this_thread::yield();
        if (++heavyPasses < 4) pool.post(heavy, false);
    };
    int lightPasses = 0;
    light.during = [&] {
        if (++lightPasses < 4) pool.post(light, false);
    };
    pool.post(heavy, false);
    pool.post(light, false);
    lightPosted = true;
    while (!pool.idle(heavy) || !pool.idle(light)) std::this_thread::yield();
    EXPECT_EQ(order, (std::vector<int>{0, 1, 0, 1, 0, 1, 0, 1}));
}

TEST(FramePool, ARemovedTaskDoesNotRunAndNotBeforeIsKept) {
    FramePool pool(2);
    std::mutex mutex;
    std::vector<int> order;
    Recorded gone(0, mutex, order), later(1, mutex, order);
    const auto start = FramePool::Clock::now();
    std::atomic<FramePool::Clock::time_point> ranAt{};
    later.during = [&] { ranAt = FramePool::Clock::now(); };
    pool.post(gone, false, start + std::chrono::milliseconds(200));
    pool.post(later, false, start + std::chrono::milliseconds(30));
    pool.remove(gone);
    pool.post(gone, true);  // ignored once removed
    pool.join(gone);
    while (!pool.idle(later)) std::this_thread::yield();
    EXPECT_EQ(order, (std::vector<int>{1}));
    EXPECT_GE(ranAt.load() - start, std::chrono::milliseconds(30));
    EXPECT_EQ(pool.workers(), 2);
}

// A later pass that yields between its bricks runs the waiting first pass inside itself, on its
// own thread (marked nested), while the pool's one worker is busy with it.
TEST(FramePool, AWaitingFirstPassRunsInsideALaterOne) {
    FramePool pool(1);
    std::mutex mutex;
    std::vector<int> order;
    Recorded first(1, mutex, order);
    std::atomic<bool> firstWasNested{false};
    first.during = [&] { firstWasNested = FramePool::nested(); };
    std::atomic<bool> laterRunning{false}, firstPosted{false};
    int ranInside = -1;
    Recorded later(0, mutex, order);
    later.during = [&] {
        laterRunning = true;
        while (!firstPosted) std::this_thread::yield();
        EXPECT_TRUE(pool.firstPassWaits());
        ranInside = pool.runFirstPassesHere(later);  // between two of its bricks
        std::lock_guard lock(mutex);
        order.push_back(2);  // the later pass goes on after it
    };
    pool.post(later, false);
    while (!laterRunning) std::this_thread::yield();
    pool.post(first, true);
    firstPosted = true;
    while (!pool.idle(later) || !pool.idle(first)) std::this_thread::yield();
    EXPECT_EQ(ranInside, 1);
    EXPECT_TRUE(firstWasNested.load());
    EXPECT_EQ(order, (std::vector<int>{0, 1, 2}));
    EXPECT_FALSE(pool.firstPassWaits());
}

// Two tasks that always have a first pass due (a client sending VIEWs without end) and a light
// one posting a later pass: the light one runs within a pass or two of each, not never (first
// passes used to go before every later one), and the heavy ones are charged for their time.
TEST(FramePool, AFloodOfFirstPassesDoesNotStarveALaterOne) {
    FramePool pool(1);
    std::mutex mutex;
    std::vector<int> order;
    std::atomic<bool> stop{false};
    Recorded a(0, mutex, order), b(1, mutex, order), light(2, mutex, order);
    for (Recorded* heavy : {&a, &b})
        heavy->during = [&pool, heavy, &stop] {
            std::this_thread::sleep_for(std::chrono::milliseconds(20));
            if (!stop) pool.post(*heavy, true);
        };
    pool.post(a, true);
    pool.post(b, true);
    std::this_thread::sleep_for(std::chrono::milliseconds(200));  // the heavy ones charged ~0.1 s each
    size_t postedAt;
    {
        std::lock_guard lock(mutex);
        postedAt = order.size();
    }
    pool.post(light, false);
    const auto giveUp = std::chrono::steady_clock::now() + std::chrono::seconds(5);
    while (!pool.idle(light) && std::chrono::steady_clock::now() < giveUp) std::this_thread::yield();
    EXPECT_TRUE(pool.idle(light)) << "the light task's pass never ran";
    stop = true;
    while (!pool.idle(a) || !pool.idle(b)) std::this_thread::yield();
    std::lock_guard lock(mutex);
    const auto ran = std::find(order.begin() + ptrdiff_t(postedAt), order.end(), 2);
    ASSERT_NE(ran, order.end());
    EXPECT_LE(ran - (order.begin() + ptrdiff_t(postedAt)), 2) << "heavy passes ran before the light one";
    EXPECT_GT(pool.charged(a), 0.05);
}

}  // namespace
}  // namespace vdiso::serve
