// The look-ahead that schedules reads for the view-dependent traversal (core/extract/brick_look_ahead.h),
// driven by hand: which bricks it hands to the readers, in which order, and that it drops
// what becomes hidden.
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <mutex>
#include <thread>
#include <vector>

#include "core/extract/brick_look_ahead.h"
#include "core/camera.h"
#include "core/trees/minmax_tree.h"
#include "core/view/occlusion_pyramid.h"
#include "core/synth/synth.h"
#include "core/extract/traversal_cursor.h"
#include "core/view/view_culler.h"
#include "core/view_presets.h"
#include "tests/extract_test_util.h"

namespace vdiso {
namespace {

constexpr double kSkin = 600.5;

// Records the bricks acquired through it (by the look-ahead's reader threads), in order.
class RecordingSource final : public BrickSource {
public:
    explicit RecordingSource(BrickSource& inner) : mInner(inner) {}
    const VolumeInfo& volume() const override { return mInner.volume(); }
    const BrickLayout& layout() const override { return mInner.layout(); }
    std::span<const BrickRange> brickRanges() const override { return mInner.brickRanges(); }
    std::span<const SubBlockCode> subBlockCodesOf(int64_t id) const override { return mInner.subBlockCodesOf(id); }
    BrickHandle acquire(int64_t id) override {
        {
            std::lock_guard lock(mMutex);
            mIds.push_back(id);
        }
        return mInner.acquire(id);  // released to the inner source, which pins
    }
    bool isResident(int64_t) const override { return resident; }
    // With `rows`, x-neighbours of a row read together (as a store's file holds them).
    bool readsTogether(int64_t a, int64_t b) const override {
        const int64_t nx = mInner.layout().brickCounts[0];
        return rows && std::abs(a - b) == 1 && a / nx == b / nx;
    }
    bool resident = false;  // what isResident says of every brick
    bool rows = false;
    std::vector<int64_t> ids() const {
        std::lock_guard lock(mMutex);
        return mIds;
    }
protected:
    void release(int64_t) override {}

private:
    BrickSource& mInner;
    mutable std::mutex mMutex;
    std::vector<int64_t> mIds;
};

// The bricks passing tests 1-3 against `culler` as it is, in the tree's front-to-back order.
std::vector<int64_t> bricksInOrder(const MinMaxTree& tree, const ViewCuller& culler) {
    std::vector<int64_t> bricks;
    std::vector<uint32_t> stack{0};
    while (!stack.empty()) {
        const uint32_t index = stack.back();
        stack.pop_back();
        const MinMaxNode& node = tree.nodes()[index];
        glm::dvec3 a, b;
        culler.nodeBox(node, a, b);
        ScreenBox box;
        if (culler.cull({node.minValue, node.maxValue}, a, b, box) != Cull::None) continue;
        if (!node.isLeaf())
            tree.pushChildrenFarFirst(stack, index, culler.eyeInBricks());
        else if (culler.subBlocksShow(tree.brickOf(node)))
            bricks.push_back(tree.brickOf(node));
    }
    return bricks;
}

struct Scene {
    std::unique_ptr<test::MemoryBrickSource> memory = test::synthBrickSource({SynthKind::Head, {64, 64, 64}}, 8);
    RecordingSource source{*memory};
    MinMaxTree tree{source.layout(), source.brickRanges()};
    Camera camera = presetCamera(ViewPreset::Normal, source.volume().origin, source.volume().worldMax(), 200, 200);
    OcclusionPyramid pyramid{200, 200};
    ViewLevels levels{source, tree, camera, pyramid, kSkin, true, 0.0};
    const ViewCuller& culler = levels.culler(0);
    Scene() { fitClipPlanes(camera, source.volume().origin, source.volume().worldMax()); }
};

// The cursor (core/extract/traversal_cursor.h) walks as the hand-written walk above: the same bricks in
// the same order, every node it pops decided once. The look-ahead and the traversal both walk
// with it, so their orders agree by construction.
TEST(TraversalCursor, WalksTheTreeFrontToBackDecidingEachNodeOnce) {
    Scene s;
    const std::vector<int64_t> order = bricksInOrder(s.tree, s.culler);
    TraversalCursor cursor(s.tree, s.levels, s.culler);
    std::vector<int64_t> bricks;
    size_t steps = 0, descended = 0;
    TraversalCursor::Step step;
    while (cursor.step(step)) {
        ++steps;
        descended += step.outcome == TraversalCursor::Outcome::Descended;
        if (step.outcome == TraversalCursor::Outcome::Brick) {
            EXPECT_TRUE(cursor.stillShows(step.node, step.at));
            bricks.push_back(step.at.id);
        }
    }
    EXPECT_TRUE(cursor.ended());
    EXPECT_EQ(bricks, order);
    // Each descended node pushed its children (8, or fewer at the volume's edges): every node
    // popped is the root or a child pushed.
    EXPECT_GT(descended, 0u);
    EXPECT_LE(steps, 1 + 8 * descended);
    // Two cursors over the same pyramid agree brick for brick.
    TraversalCursor again(s.tree, s.levels, s.culler);
    std::vector<int64_t> second;
    while (again.nextBrick(step)) second.push_back(step.at.id);
    EXPECT_EQ(second, order);
}

// Driven through a whole traversal (nothing drawn, so nothing becomes hidden): the readers get
// bricks the traversal visits, in its order, each once, never one it has passed.
TEST(BrickLookAhead, ReadsBricksOfTheTraversalInItsOrderEachOnce) {
    Scene s;
    const std::vector<int64_t> order = bricksInOrder(s.tree, s.culler);
    ASSERT_GT(order.size(), 10u);
    std::vector<int64_t> read;
    {
        BrickLookAhead ahead(s.source, s.tree, s.levels, 4, 1);
        for (int64_t b : order) {
            ahead.beforeAcquire(b);
            // Let the reader catch up, so the reads show what was handed over when.
            std::this_thread::sleep_for(std::chrono::milliseconds(2));
        }
        read = s.source.ids();
        ahead.stop();
    }
    EXPECT_EQ(s.memory->pinned(), 0);  // stop released every pin
    ASSERT_FALSE(read.empty());
    size_t at = 0;
    for (const int64_t b : read) {
        const auto it = std::find(order.begin() + ptrdiff_t(at), order.end(), b);
        ASSERT_NE(it, order.end()) << "brick " << b << " read out of order or twice";
        at = size_t(it - order.begin()) + 1;
    }
}

TEST(BrickLookAhead, HiddenBricksAreNotRead) {
    Scene s;
    const std::vector<int64_t> order = bricksInOrder(s.tree, s.culler);
    ASSERT_GT(order.size(), 10u);
    BrickLookAhead ahead(s.source, s.tree, s.levels, 16, 1);
    // The whole image is covered before the look-ahead starts: every brick after the first is
    // hidden, so nothing is read ahead.
    for (int y = 0; y < 200; ++y) s.pyramid.coverSpan(y, 0, 199);
    s.pyramid.propagate();
    ahead.beforeAcquire(order[0]);
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
    EXPECT_TRUE(s.source.ids().empty());
    ahead.stop();
    EXPECT_EQ(ahead.readUnused(), 0u);
}

// The coverage here comes from no brick (as a CoverageExchange's does): the look-ahead is told
// so, and tests every brick ahead again, not only those meeting the brick acquired last.
TEST(BrickLookAhead, BricksHiddenAfterTheyWereFoundAreDropped) {
    Scene s;
    const std::vector<int64_t> order = bricksInOrder(s.tree, s.culler);
    BrickLookAhead ahead(s.source, s.tree, s.levels, 16, 1, BrickLookAhead::kNearBricks, true);
    ahead.beforeAcquire(order[0]);
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
    const size_t before = s.source.ids().size();
    // Now everything is covered: bricks found but not handed over are cancelled, and moving on
    // to the next brick hands nothing more to the readers.
    for (int y = 0; y < 200; ++y) s.pyramid.coverSpan(y, 0, 199);
    s.pyramid.propagate();
    ahead.beforeAcquire(order[1]);
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
    EXPECT_EQ(s.source.ids().size(), before);
    ahead.stop();
}

// Bricks already in memory when they are found are not handed to the readers: the same walk
// that reads some bricks ahead when the source holds none reads nothing when it holds all.
TEST(BrickLookAhead, ResidentBricksAreNotReadAhead) {
    for (const bool resident : {false, true}) {
        Scene s;
        s.source.resident = resident;
        const std::vector<int64_t> order = bricksInOrder(s.tree, s.culler);
        BrickLookAhead ahead(s.source, s.tree, s.levels, 8, 1);
        for (int64_t b : order) {
            ahead.beforeAcquire(b);
            std::this_thread::sleep_for(std::chrono::milliseconds(2));
        }
        const size_t read = s.source.ids().size();
        ahead.stop();
        if (resident)
            EXPECT_EQ(read, 0u);
        else
            EXPECT_GT(read, 0u);
    }
}

// Where a read waits a round trip, a brick handed to the readers is read with its neighbours
// along x that show, before the traversal has found them (it finds one brick ahead here): a row
// of the visible surface in one read. Every brick read shows, and is read once. A disk's
// look-ahead reads only bricks it has found.
TEST(BrickLookAhead, OverTheNetworkABrickIsReadWithItsNeighboursThatShow) {
    for (const size_t near : {BrickLookAhead::kNearBricks, BrickLookAhead::kNearBricks + 30}) {
        Scene s;
        s.source.rows = true;
        const std::vector<int64_t> order = bricksInOrder(s.tree, s.culler);
        ASSERT_GT(order.size(), 10u);
        size_t readBeforeFound = 0;
        std::vector<int64_t> read;
        {
            BrickLookAhead ahead(s.source, s.tree, s.levels, 1, 1, near);
            for (size_t i = 0; i < order.size(); ++i) {
                ahead.beforeAcquire(order[i]);  // found so far: order[0 .. i + 1]
                std::this_thread::sleep_for(std::chrono::milliseconds(3));
                const auto found = order.begin() + ptrdiff_t(std::min(i + 2, order.size()));
                const int64_t nx = s.source.layout().brickCounts[0];
                for (const int64_t b : s.source.ids()) {
                    if (std::find(order.begin(), found, b) != found) continue;
                    ++readBeforeFound;
                    // Read beside a brick found already: in its row, at most kBeside away.
                    EXPECT_TRUE(std::any_of(order.begin(), found, [&](int64_t f) {
                        return f / nx == b / nx && std::abs(f - b) <= BrickLookAhead::kBeside;
                    })) << "brick " << b << " read before it was found, beside no brick found";
                }
                if (readBeforeFound > 0) break;
            }
            read = s.source.ids();
            ahead.stop();
        }
        for (const int64_t b : read) EXPECT_NE(std::find(order.begin(), order.end(), b), order.end()) << b;
        std::sort(read.begin(), read.end());
        EXPECT_EQ(std::adjacent_find(read.begin(), read.end()), read.end()) << "a brick read twice";
        if (near == BrickLookAhead::kNearBricks)
            EXPECT_EQ(readBeforeFound, 0u);
        else
            EXPECT_GT(readBeforeFound, 0u);
    }
}

TEST(BrickLookAhead, DepthZeroReadsNothing) {
    Scene s;
    const std::vector<int64_t> order = bricksInOrder(s.tree, s.culler);
    BrickLookAhead ahead(s.source, s.tree, s.levels, 0);
    for (int64_t b : order) ahead.beforeAcquire(b);
    ahead.stop();
    EXPECT_TRUE(s.source.ids().empty());
}

}  // namespace
}  // namespace vdiso
