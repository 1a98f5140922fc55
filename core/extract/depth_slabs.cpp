#include "core/extract/depth_slabs.h"

#include <algorithm>
#include <cmath>

#include "core/kernel/iso.h"

namespace vdiso {

BrickRegion DepthSlabs::region(int s, const BrickLayout& layout) const {
    BrickRegion r;
    for (int a = 0; a < 3; ++a) r.hi[a] = layout.brickCounts[a];
    r.lo[axis] = cuts[size_t(s)];
    r.hi[axis] = cuts[size_t(s) + 1];
    return r;
}

DepthSlabs depthSlabs(const BrickSource& source, const Camera& camera, double iso, int slabs) {
    const BrickLayout& layout = source.layout();
    const VolumeInfo& volume = source.volume();
    const glm::dvec3 forward = camera.forward();
    DepthSlabs d;
    d.axis = 0;
    for (int a = 1; a < 3; ++a)
        if (std::abs(forward[a]) > std::abs(forward[d.axis])) d.axis = a;
    const int axis = d.axis;
    const int64_t layers = layout.brickCounts[axis];

    // Active bricks per layer along the axis.
    std::vector<uint64_t> weight(size_t(layers), 0);
    const std::span<const BrickRange> ranges = source.brickRanges();
    uint64_t total = 0;
    for (int64_t id = 0; id < layout.brickCount(); ++id) {
        if (!rangeHoldsIso(ranges[size_t(id)].minValue, ranges[size_t(id)].maxValue, iso)) continue;
        ++weight[size_t(layout.brickCoord(id)[axis])];
        ++total;
    }
    // Slab k ends where the running weight reaches k + 1 shares: after one layer at least, and
    // leaving one for each later slab, while layers last.
    d.cuts.push_back(0);
    uint64_t running = 0;
    int64_t layer = 0;
    for (int k = 0; k + 1 < slabs; ++k) {
        const int64_t least = std::min(layers, layer + 1);
        const int64_t most = std::max(least, layers - (slabs - 1 - k));
        while (layer < least || (layer < most && running * uint64_t(slabs) < total * uint64_t(k + 1)))
            running += weight[size_t(layer++)];
        d.cuts.push_back(layer);
    }
    d.cuts.push_back(layers);

    // The eye's slab: where its coordinate along the axis falls, in bricks.
    const double eye = (camera.eye[axis] - volume.origin[axis]) / (volume.spacing[axis] * layout.brickSize);
    d.eyeSlab = 0;
    for (int s = 0; s < slabs; ++s)
        if (eye >= double(d.cuts[size_t(s)])) d.eyeSlab = s;
    return d;
}

}  // namespace vdiso
