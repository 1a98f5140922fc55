#include "core/lod/view_levels.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "core/kernel/iso.h"

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
    : mTree(tree), mIso(iso), mLodError(lodError), mEye(camera.eye), mForward(camera.forward()),
      mFocalPixels(double(camera.height) / (2.0 * std::tan(glm::radians(camera.fovYDegrees) / 2.0))) {
    const int levels = lodError > 0 ? tree.levelCount() : 1;
    for (int l = 0; l < levels; ++l)
        mLevels.push_back(std::make_unique<Level>(source, l, camera, pyramid, iso, estimateBox));
}

void ViewLevels::confineTo(const BrickRegion* region) {
    if (region && mLevels.size() > 1)
        throw std::invalid_argument("a region of the volume is extracted at full resolution only (lod error 0)");
    mRegion = region;
}

double ViewLevels::leastDepth(const glm::dvec3& a, const glm::dvec3& b) const {
    double depth = INFINITY;
    for (int k = 0; k < 8; ++k) {
        const glm::dvec3 corner{(k & 1) ? b.x : a.x, (k & 2) ? b.y : a.y, (k & 4) ? b.z : a.z};
        depth = std::min(depth, glm::dot(corner - mEye, mForward));
    }
    return depth;
}

double ViewLevels::largestCellPixels(int level) const {
    const VolumeInfo& v = mLevels[0]->source.volume();
    const int64_t lo[3] = {0, 0, 0}, hi[3] = {v.dims[0] - 1, v.dims[1] - 1, v.dims[2] - 1};
    glm::dvec3 a, b;
    mLevels[0]->culler.worldBox(lo, hi, a, b);
    const double depth = leastDepth(a, b);
    return depth > 0.0 ? mLevels[size_t(level)]->cellSize * mFocalPixels / depth : INFINITY;
}

int ViewLevels::levelOf(const MinMaxNode& node, const glm::dvec3& a, const glm::dvec3& b) const {
    if (count() == 1 || node.coarseLevel == MinMaxNode::kNoLevel) return 0;
    const double depth = leastDepth(a, b);
    if (!(depth > 0.0)) return 0;
    const int coarsest = std::min<int>(node.coarseLevel, count() - 1);
    for (int l = coarsest; l >= std::max<int>(node.fineLevel, 1); --l)
        if (mLevels[size_t(l)]->cellSize * mFocalPixels / depth <= mLodError && holdsIso(node, l)) return l;
    return 0;
}

bool ViewLevels::holdsIso(const MinMaxNode& node, int l) const {
    const Brick at = brickOf(node, l);
    const BrickRange r = mLevels[size_t(l)]->source.brickRanges()[size_t(at.local)];
    return rangeHoldsIso(r.minValue, r.maxValue, mIso);
}

int ViewLevels::levelAt(const int64_t c[3]) const {
    uint32_t node;
    Brick at;
    return resolve(c, node, at) ? at.level : -1;
}

bool ViewLevels::resolve(const int64_t c[3], uint32_t& index, Brick& at) const {
    const std::span<const MinMaxNode> nodes = mTree.nodes();
    index = 0;
    while (true) {
        const MinMaxNode& node = nodes[index];
        if (!rangeHoldsIso(node.minValue, node.maxValue, mIso)) return false;
        glm::dvec3 a, b;
        culler(0).nodeBox(node, a, b);
        const int level = levelOf(node, a, b);
        if (level > 0 || node.isLeaf()) {
            at = brickOf(node, level);
            return true;
        }
        index = mTree.childHolding(index, c);
    }
}

unsigned ViewLevels::innerFaces(const MinMaxNode& node) const {
    const Dims3& bricks = mTree.layout().brickCounts;
    unsigned faces = 0;
    for (int a = 0; a < 3; ++a) {
        if (node.lo[a] > 0) faces |= 1u << (2 * a);
        if (node.hi[a] < bricks[a]) faces |= 1u << (2 * a + 1);
    }
    return faces;
}

unsigned ViewLevels::seamFaces(const MinMaxNode& node, int level) const {
    if (count() == 1) return 0;
    unsigned faces = 0;
    for (int a = 0; a < 3; ++a) {
        const int u = (a + 1) % 3, v = (a + 2) % 3;
        for (int upper = 0; upper < 2; ++upper) {
            const unsigned bit = 1u << (2 * a + upper);
            if (!(innerFaces(node) & bit)) continue;
            int64_t c[3];
            c[a] = upper ? node.hi[a] : node.lo[a] - 1;
            for (c[u] = node.lo[u]; c[u] < node.hi[u] && !(faces & bit); ++c[u])
                for (c[v] = node.lo[v]; c[v] < node.hi[v] && !(faces & bit); ++c[v]) {
                    const int other = levelAt(c);
                    if (other >= 0 && other != level) faces |= bit;
                }
        }
    }
    return faces;
}

}  // namespace vdiso
