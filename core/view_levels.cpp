#include "core/view_levels.h"

#include <algorithm>
#include <cmath>

#include <glm/geometric.hpp>
#include <glm/trigonometric.hpp>

namespace vdiso {

ViewLevels::Level::Level(BrickSource& base, int l, const Camera& camera, const OcclusionPyramid& pyramid,
                         double iso, bool estimateBox)
    : source(base, l), culler(source, camera, pyramid, iso, estimateBox) {
    const glm::dvec3& s = source.volume().spacing;
    cellSize = std::max({s.x, s.y, s.z});
}

ViewLevels::ViewLevels(BrickSource& source, const MinMaxTree& tree, const Camera& camera,
                       const OcclusionPyramid& pyramid, double iso, bool estimateBox, double lodError)
    : mTree(tree), mLodError(lodError), mEye(camera.eye), mForward(camera.forward()),
      mFocalPixels(double(camera.height) / (2.0 * std::tan(glm::radians(camera.fovYDegrees) / 2.0))) {
    const int levels = lodError > 0 ? tree.levelCount() : 1;
    for (int l = 0; l < levels; ++l)
        mLevels.push_back(std::make_unique<Level>(source, l, camera, pyramid, iso, estimateBox));
}

int ViewLevels::levelOf(const MinMaxNode& node, const glm::dvec3& a, const glm::dvec3& b) const {
    if (count() == 1 || node.coarseLevel == MinMaxNode::kNoLevel) return 0;
    double depth = INFINITY;  // the least view depth of the box's corners
    for (int k = 0; k < 8; ++k) {
        const glm::dvec3 corner{(k & 1) ? b.x : a.x, (k & 2) ? b.y : a.y, (k & 4) ? b.z : a.z};
        depth = std::min(depth, glm::dot(corner - mEye, mForward));
    }
    if (!(depth > 0.0)) return 0;
    const int coarsest = std::min<int>(node.coarseLevel, count() - 1);
    for (int l = coarsest; l >= std::max<int>(node.fineLevel, 1); --l)
        if (mLevels[size_t(l)]->cellSize * mFocalPixels / depth <= mLodError) return l;
    return 0;
}

}  // namespace vdiso
