#include "core/extract/traversal_cursor.h"

namespace vdiso {

TraversalCursor::TraversalCursor(const MinMaxTree& tree, const ViewLevels& levels, const ViewCuller& culler)
    : mTree(tree), mLevels(levels), mCuller(culler) {
    if (!tree.nodes().empty()) mStack.push_back(0);
}

bool TraversalCursor::step(Step& s) {
    if (mStack.empty()) return false;
    s.node = mStack.back();
    mStack.pop_back();
    const MinMaxNode& node = mTree.nodes()[s.node];
    s.cull = Cull::None;
    if (mLevels.outsideRegion(node)) {
        s.outcome = Outcome::OutsideRegion;
        return true;
    }
    mCuller.nodeBox(node, s.a, s.b);
    s.cull = mCuller.cull({node.minValue, node.maxValue}, s.a, s.b, s.box);
    if (s.cull != Cull::None) {
        s.outcome = Outcome::Culled;
        return true;
    }
    const int level = mLevels.levelOf(node, s.a, s.b);
    if (level == 0 && !node.isLeaf()) {
        mTree.pushChildrenFarFirst(mStack, s.node, mCuller.eyeInBricks());
        s.outcome = Outcome::Descended;
        return true;
    }
    s.at = mLevels.brickOf(node, level);
    s.outcome = mLevels.shows(s.at) ? Outcome::Brick : Outcome::NotShown;
    return true;
}

bool TraversalCursor::stillShows(uint32_t index, const ViewLevels::Brick& at, ScreenBox* box) const {
    const MinMaxNode& node = mTree.nodes()[index];
    glm::dvec3 a, b;
    mCuller.nodeBox(node, a, b);
    ScreenBox own;
    return mCuller.cull({node.minValue, node.maxValue}, a, b, box ? *box : own) == Cull::None && mLevels.shows(at);
}

}  // namespace vdiso
