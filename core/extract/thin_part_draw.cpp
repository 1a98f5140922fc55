#include "core/extract/thin_part_draw.h"

namespace vdiso {

bool ThinPartDraw::pixelOf(const glm::dvec3& position, glm::ivec2& pixel) const {
    const glm::dvec3 p = mPixels.project(position);
    if (!(p.z >= 0.0 && p.z <= 1.0 && p.x >= 0.0 && p.y >= 0.0 && p.x < mPyramid.width() && p.y < mPyramid.height()))
        return false;
    pixel = {int(p.x), int(p.y)};
    return true;
}

bool ThinPartDraw::take(const glm::dvec3& position) {
    glm::ivec2 pixel;
    if (!pixelOf(position, pixel) || mPyramid.isCovered(pixel.x, pixel.y)) return false;
    if (!pixelOf(glm::dvec3(glm::vec3(position)), pixel)) return false;  // as it is stored
    if (mTaken.empty()) mTaken.assign((size_t(mPyramid.width()) * size_t(mPyramid.height()) + 63) / 64, 0);
    const size_t bit = bitOf(pixel);
    uint64_t& word = mTaken[bit / 64];
    const uint64_t mask = uint64_t(1) << (bit % 64);
    if (word & mask) return false;
    word |= mask;
    return true;
}

int64_t ThinPartDraw::draw(PointSet& points) {
    int64_t drawn = 0;
    for (size_t k = 0; k < mWaiting.size(); ++k) {
        glm::ivec2 p;
        if (!pixelOf(glm::dvec3(mWaiting.positions[k]), p)) continue;
        const size_t bit = bitOf(p);
        mTaken[bit / 64] &= ~(uint64_t(1) << (bit % 64));
        if (mPyramid.isCovered(p.x, p.y)) continue;  // covered by what came after
        points.positions.push_back(mWaiting.positions[k]);
        points.normals.push_back(mWaiting.normals[k]);
        mPyramid.coverSpan(p.y, p.x, p.x);
        ++drawn;
    }
    mPyramid.propagate();
    mWaiting.clear();
    return drawn;
}

}  // namespace vdiso
