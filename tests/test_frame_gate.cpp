// The frame gate of vdiso serve (serve/viewer_session.h): at most its slots' frames at once;
// waiting ones go in the order they came, every coarse pass before any final one; one that gives
// up leaves its place to the next.
#include <gtest/gtest.h>

#include <atomic>
#include <mutex>
#include <thread>
#include <vector>

#include "serve/viewer_session.h"

namespace vdiso::serve {
namespace {

TEST(FrameGate, CoarsePassesGoFirstThenEachInTurn) {
    FrameGate gate(1);
    ASSERT_TRUE(gate.enter([] { return false; }));  // the slot is taken
    std::mutex mutex;
    std::vector<int> order;
    std::vector<std::thread> waiting;
    // Finals 0 and 1 come first, then coarse 2 and 3, each once the one before waits.
    for (int k = 0; k < 4; ++k) {
        waiting.emplace_back([&, k] {
            if (!gate.enter([] { return false; }, k >= 2)) return;
            {
                std::lock_guard lock(mutex);
                order.push_back(k);
            }
            gate.leave();
        });
        while (gate.waiting() < size_t(k + 1)) std::this_thread::yield();
    }
    gate.leave();
    for (std::thread& t : waiting) t.join();
    EXPECT_EQ(order, (std::vector<int>{2, 3, 0, 1}));
    EXPECT_EQ(gate.entered(), 5u);
}

TEST(FrameGate, OneThatGivesUpLeavesItsPlace) {
    FrameGate gate(1);
    ASSERT_TRUE(gate.enter([] { return false; }));
    std::atomic<bool> superseded{false};
    std::atomic<int> stage{0};
    std::thread first([&] { EXPECT_FALSE(gate.enter([&] { return superseded.load(); })); stage = 1; });
    while (gate.waiting() < 1) std::this_thread::yield();
    std::thread second([&] {
        EXPECT_TRUE(gate.enter([] { return false; }));
        stage = 2;
        gate.leave();
    });
    while (gate.waiting() < 2) std::this_thread::yield();
    superseded = true;  // the first gives up; the second still waits for the slot
    first.join();
    EXPECT_EQ(stage.load(), 1);
    gate.leave();
    second.join();
    EXPECT_EQ(stage.load(), 2);
}

}  // namespace
}  // namespace vdiso::serve
