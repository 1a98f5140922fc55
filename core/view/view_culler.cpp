#include "core/view/view_culler.h"

#include <cmath>

#include "core/kernel/iso.h"
#include "core/trees/sub_blocks.h"

namespace vdiso {

ViewCuller::ViewCuller(const BrickSource& source, const Camera& camera, const OcclusionPyramid& pyramid,
                       double iso, bool estimateBox)
    : mSource(source), mCamera(camera), mPyramid(pyramid), mIso(iso), mEstimateBox(estimateBox),
      mProjector(camera), mImage(camera.width, camera.height), mGridToClip(camera.viewProjection() * source.volume().gridToWorld()) {
    const VolumeInfo& volume = source.volume();
    for (int k = 0; k < 3; ++k)
        mEyeInBricks[k] = (camera.eye[k] - volume.origin[k]) / volume.spacing[k] / double(source.layout().brickSize);
}

void ViewCuller::worldBox(const int64_t lo[3], const int64_t hi[3], glm::dvec3& a, glm::dvec3& b) const {
    const VolumeInfo& volume = mSource.volume();
    for (int k = 0; k < 3; ++k) {
        a[k] = volume.origin[k] + double(lo[k]) * volume.spacing[k];
        b[k] = volume.origin[k] + double(std::min(hi[k], volume.dims[k] - 1)) * volume.spacing[k];
    }
}

void ViewCuller::nodeBox(const MinMaxNode& node, glm::dvec3& a, glm::dvec3& b) const {
    const int64_t B = mSource.layout().brickSize;
    const int64_t lo[3] = {node.lo[0] * B, node.lo[1] * B, node.lo[2] * B};
    const int64_t hi[3] = {node.hi[0] * B, node.hi[1] * B, node.hi[2] * B};
    worldBox(lo, hi, a, b);
}

bool ViewCuller::subBlocksShow(int64_t brick) const {
    const std::span<const SubBlockCode> codes = mSource.subBlockCodesOf(brick);
    if (codes.empty()) return true;
    const BrickLayout& layout = mSource.layout();
    const BrickRange whole = mSource.brickRanges()[size_t(brick)];
    const Dims3 c = layout.brickCoord(brick);
    const int C = subBlockCells(layout.brickSize);
    for (int s = 0; s < kSubBlocksPerBrick; ++s) {
        const BrickRange range = decodeSubBlockRange(codes[size_t(s)], whole);
        if (!rangeHoldsIso(range.minValue, range.maxValue, mIso)) continue;
        const int block[3] = {s % kSubBlocksPerAxis, s / kSubBlocksPerAxis % kSubBlocksPerAxis,
                              s / (kSubBlocksPerAxis * kSubBlocksPerAxis)};
        int64_t lo[3], hi[3];
        for (int k = 0; k < 3; ++k) {
            const int64_t first = c[k] * layout.brickSize;
            lo[k] = first + int64_t(block[k]) * C;
            hi[k] = std::min(lo[k] + C, first + layout.cellsOnAxis(k, c[k]));
        }
        glm::dvec3 a, b;
        worldBox(lo, hi, a, b);
        ScreenBox box;
        if (cull(range, a, b, box) == Cull::None) return true;
    }
    return false;
}

}  // namespace vdiso
