#include "core/extract/brick_look_ahead.h"

#include <algorithm>

namespace vdiso {

BrickLookAhead::BrickLookAhead(BrickSource& source, const MinMaxTree& tree, const ViewLevels& levels,
                               size_t depth, int readers, size_t near, bool coverageFromElsewhere)
    : mSource(source), mTree(tree), mLevels(levels), mCursor(tree, levels, levels.culler(0)), mDepth(depth), mNear(near),
      mPrefetcher(source, depth, readers), mCoverageFromElsewhere(coverageFromElsewhere),
      mDrawn{0, 0, levels.culler(0).camera().width - 1, levels.culler(0).camera().height - 1} {}

bool BrickLookAhead::findNext() {
    TraversalCursor::Step step;
    if (mDepth == 0 || !mCursor.nextBrick(step)) return false;
    // Found now, it is read in its own turn (or with a run as found bricks are): no brick offers
    // it beside itself any longer, so that it is never read unpinned ahead of its turn.
    if (mNear > kNearBricks)
        for (AheadBrick& ahead : mAhead) {
            int64_t* end = std::remove(ahead.beside, ahead.beside + ahead.besideCount, step.at.id);
            ahead.besideCount = int(end - ahead.beside);
        }
    mAhead.push_back({step.node, step.at, step.at.id, mCursor.culler().pixelRect(step.box),
                      mSource.isResident(step.at.id) ? kResident : kNotPushed});
    if (mNear > kNearBricks && mAhead.back().item != kResident) findBeside(mAhead.back());
    return true;
}

void BrickLookAhead::findBeside(AheadBrick& ahead) {
    // Only the side away from the eye: the tree splits x between two neighbours, and the walk
    // takes the eye's side first, so a neighbour on the eye's side is decided already (found
    // ahead, extracted or culled). Each side stops at a neighbour that does not show now, lies
    // outside the region, is found already, or lies mostly behind this brick on screen (a view
    // along x: hidden once this one is drawn, it is not read on speculation).
    const std::span<const MinMaxNode> nodes = mTree.nodes();
    const int64_t bricksX = mTree.layout().brickCounts[0];
    const double eyeX = mCursor.culler().eyeInBricks()[0];
    const MinMaxNode& self = nodes[ahead.node];
    for (const int side : {-1, 1}) {
        if (side < 0 ? eyeX < double(self.lo[0]) : eyeX >= double(self.hi[0])) continue;
        const MinMaxNode* from = &self;
        for (int k = 0; k < kBeside; ++k) {
            const int64_t c[3] = {side < 0 ? int64_t(from->lo[0]) - 1 : int64_t(from->hi[0]), from->lo[1], from->lo[2]};
            if (c[0] < 0 || c[0] >= bricksX) break;
            uint32_t node;
            ViewLevels::Brick at;
            ScreenBox box;
            if (!mLevels.resolve(c, node, at) || at.level != ahead.at.level || mLevels.outsideRegion(nodes[node]) ||
                !mCursor.stillShows(node, at, &box))
                break;
            if (std::any_of(mAhead.begin(), mAhead.end(), [&](const AheadBrick& a) { return a.brick == at.id; })) break;
            const PixelRect rect = mCursor.culler().pixelRect(box);
            if (mostlyBehind(rect, ahead.rect)) break;
            ahead.beside[ahead.besideCount++] = at.id;
            from = &nodes[node];
        }
    }
}

int64_t BrickLookAhead::pixelsOf(const PixelRect& r) const {
    const Camera& camera = mCursor.culler().camera();
    const int64_t w = std::min(r.x1, camera.width - 1) - std::max(r.x0, 0) + 1;
    const int64_t h = std::min(r.y1, camera.height - 1) - std::max(r.y0, 0) + 1;
    return w > 0 && h > 0 ? w * h : int64_t(0);
}

bool BrickLookAhead::mostlyBehind(const PixelRect& a, const PixelRect& b) const {
    return a.overlaps(b) && 2 * pixelsOf(a.intersection(b)) > pixelsOf(a);
}

void BrickLookAhead::beforeAcquire(int64_t brick) {
    if (mDepth == 0) return;
    while (true) {
        while (!mAhead.empty() && mAhead.front().brick != brick) mAhead.pop_front();
        if (!mAhead.empty() || !findNext()) break;
    }
    const Camera& camera = mCursor.culler().camera();
    PixelRect current{0, 0, camera.width - 1, camera.height - 1};
    if (!mAhead.empty()) {
        current = mAhead.front().rect;
        if (pushed(mAhead.front().item)) mPrefetcher.consumed(mAhead.front().item);
        mAhead.pop_front();
    }
    // Coverage grew only within the brick acquired last: a brick ahead whose rectangle misses
    // that one's shows as it did at its last test.
    std::erase_if(mAhead, [&](const AheadBrick& ahead) {
        if (ahead.item == kResident) return false;  // nothing to cancel: not tested again
        if (!mCoverageFromElsewhere && !ahead.rect.overlaps(mDrawn)) return false;
        if (mCursor.stillShows(ahead.node, ahead.at)) return false;
        if (pushed(ahead.item)) mPrefetcher.cancel(ahead.item);
        return true;
    });
    mDrawn = current;  // what the brick acquired now can draw
    while (mAhead.size() < mDepth && findNext()) {
    }
    auto harmless = [&](const PixelRect& a, const PixelRect& b) {
        if (!a.overlaps(b)) return true;
        const PixelRect both = a.intersection(b);
        return mCursor.culler().occluded(both);
    };
    for (size_t k = 0; k < mAhead.size(); ++k) {
        AheadBrick& ahead = mAhead[k];
        if (ahead.item != kNotPushed) continue;
        bool settled = harmless(ahead.rect, current);
        for (size_t j = 0; j < k && settled; ++j) settled = harmless(ahead.rect, mAhead[j].rect);
        // (A brick mostly behind the current one is not read on speculation: hidden once that one
        // is drawn, in closeups.)
        if (!settled && (k >= mNear || mostlyBehind(ahead.rect, current))) break;
        ahead.item = mPrefetcher.push(ahead.brick);
    }
    mPrefetcher.publish();  // read from here on, gathered into runs among themselves
    // Where a read waits a round trip, the bricks found but not settled ride along with a run
    // they lie next to in the file.
    if (mNear > kNearBricks) {
        std::vector<int64_t> unsettled;
        for (const AheadBrick& ahead : mAhead) {
            if (ahead.item == kNotPushed) unsettled.push_back(ahead.brick);
            unsettled.insert(unsettled.end(), ahead.beside, ahead.beside + ahead.besideCount);
        }
        mPrefetcher.offer(std::move(unsettled));
    }
}

}  // namespace vdiso
