// Prefetch scheduling for the view-dependent traversal: which bricks to read ahead of it, and
// when (docs/design.md, "Memory and reads").
//
// A second cursor (core/extract/traversal_cursor.h: the traversal's own walk) runs ahead of the
// traversal, with tests 1-3 against the pyramid as it is now. Coverage only grows, so
// every brick the traversal will acquire is found by the look-ahead first; a brick it finds may
// still be hidden by the time the traversal gets there (then it was read for nothing, and
// counted by readUnused).
//
// Each time the traversal is about to acquire a brick (beforeAcquire), bricks found ahead that
// it skipped are hidden by now and their pins go; those still ahead whose screen rectangle meets
// the brick acquired last (the only place coverage grew since their last test, unless coverage
// also comes from elsewhere) are tested again and dropped once hidden (cancelled if not read yet); the cursor moves on to keep `depth` bricks
// found; and bricks are handed to the reader threads, in order, while each is settled: where
// its screen box meets this brick's or any earlier one's, every pixel is covered already, so
// nothing drawn before its turn can hide it and reading it now cannot be wasted. The next
// `near` (kNearBricks) go regardless, so reads keep ahead where boxes overlap, unless most of one's box
// lies in this brick's (closeups: it is likely behind this one and hidden by it). A brick the
// source holds in memory already when it is found is neither handed over nor tested again (a
// warm cache would otherwise wake a reader per brick, and re-test the bricks ahead at every
// brick, for nothing); if it is evicted before its turn, the traversal reads it itself.
// Where a read waits a round trip (`near` beyond kNearBricks), the bricks found but not settled
// are offered to the readers (BrickPrefetcher::offer): read with a run they lie next to in the
// file, in its request rather than one of their own later. So are a found brick's neighbours
// along x on the side away from the eye (up to kBeside, as far as each shows when the brick is
// found: the traversal extracts it at the same level, it passes tests 1-3 and lies mostly
// beside this brick on screen, not behind it), which the traversal's front-to-back walk reaches
// from another subtree, often many bricks later: a row of the visible surface in one request
// where it took several.
// One look-ahead per traversal thread.
#pragma once

#include <cstddef>
#include <cstdint>
#include <deque>
#include <vector>

#include "core/extract/brick_prefetcher.h"
#include "core/brick_source.h"
#include "core/trees/minmax_tree.h"
#include "core/extract/traversal_cursor.h"
#include "core/view/view_culler.h"
#include "core/lod/view_levels.h"

namespace vdiso {

// How far ahead a traversal reads a store over the network, where a request waits a round trip
// where a disk read waits a seek, so many more are kept in flight: `bricks` bricks found ahead,
// of which `near` are read before they are known to show, and per image strip `readers` reader
// threads where each waits on its read (an indexed array's chunks); a store's own bricks load in
// the background, two readers a strip keeping as many in flight as the link holds
// (BrickPrefetcher). vdiso extract and vdiso serve both read a remote store so.
struct RemoteReadAhead {
    static constexpr int kReaders = 32, kBricks = 128, kNear = 64;
};

class BrickLookAhead {
public:
    static constexpr size_t kNearBricks = 2;
    static constexpr int kBeside = 4;

    // depth 0: nothing is read ahead (every call does nothing). `near`: the bricks next in
    // turn handed over unsettled (kNearBricks for a disk; more where a read waits a round trip).
    // coverageFromElsewhere: the pyramid also gains coverage the traversal's bricks did not draw
    // (CoverageExchange), so every brick ahead is tested again at every step.
    BrickLookAhead(BrickSource& source, const MinMaxTree& tree, const ViewLevels& levels,
                   size_t depth, int readers = BrickPrefetcher::kDefaultReaders,
                   size_t near = kNearBricks, bool coverageFromElsewhere = false);

    // The traversal is about to acquire `brick` (it acquires it itself).
    void beforeAcquire(int64_t brick);
    // The traversal has ended: reading stops and every pin goes.
    void stop() { mPrefetcher.stop(); }
    // Bricks read ahead and then not used: hidden before the traversal came.
    size_t readUnused() const { return mPrefetcher.skippedLoaded(); }

private:
    static constexpr size_t kNotPushed = SIZE_MAX;
    static constexpr size_t kResident = SIZE_MAX - 1;  // in memory when its turn came: not read
    static bool pushed(size_t item) { return item < kResident; }
    struct AheadBrick {
        uint32_t node;
        ViewLevels::Brick at;
        int64_t brick;  // at.id
        PixelRect rect;
        size_t item = kNotPushed;  // in the prefetcher's list, once handed to it (or kResident)
        int besideCount = 0;       // where a read waits a round trip: neighbours offered with it
        int64_t beside[2 * kBeside] = {};
    };
    // Where a read waits a round trip: the found brick's neighbours that show, into its `beside`.
    void findBeside(AheadBrick& ahead);
    // Moves the cursor on to the next brick that passes tests 1-3 now; false at the end.
    bool findNext();
    int64_t pixelsOf(const PixelRect& r) const;
    // Whether most of a's pixels lie in b's: a brick there is likely behind b, hidden once b is
    // drawn (closeups; a view along x for b's neighbours).
    bool mostlyBehind(const PixelRect& a, const PixelRect& b) const;

    BrickSource& mSource;
    const MinMaxTree& mTree;
    const ViewLevels& mLevels;
    TraversalCursor mCursor;  // the traversal's walk, run ahead of it
    size_t mDepth;
    size_t mNear;
    BrickPrefetcher mPrefetcher;
    std::deque<AheadBrick> mAhead;  // found, in the traversal's order
    bool mCoverageFromElsewhere;
    // The pixel centres the brick acquired last can have covered (its box's); at first, all.
    PixelRect mDrawn;
};

}  // namespace vdiso
