// The walk over a brick's meta-cells that the view-dependent traversal takes inside each brick
// (core/extract/extract_view.cpp): boxes of meta-cells [lo, hi), front to back by halving the longest
// side, the half on the eye's side first, the same exact order as the tree's above the brick.
// The visitor decides each box before it is refined: enter(lo, hi) is false to stop there
// (culled, drawn as a point, or made without scan conversion); a box of one meta-cell that is
// entered goes to extract(lo).
#pragma once

#include <glm/vec3.hpp>

namespace vdiso {

// `eyeCell`: the eye in the brick's cell coordinates; `metaCellSize`: cells per meta-cell side.
template <class Visitor>
void walkMetaCells(const int lo[3], const int hi[3], int metaCellSize, const glm::dvec3& eyeCell, Visitor& visitor) {
    if (!visitor.enter(lo, hi)) return;
    if (hi[0] - lo[0] == 1 && hi[1] - lo[1] == 1 && hi[2] - lo[2] == 1) {
        visitor.extract(lo);
        return;
    }
    int axis = 0;
    for (int k = 1; k < 3; ++k)
        if (hi[k] - lo[k] > hi[axis] - lo[axis]) axis = k;
    const int mid = (lo[axis] + hi[axis]) / 2;
    int firstHi[3] = {hi[0], hi[1], hi[2]}, secondLo[3] = {lo[0], lo[1], lo[2]};
    firstHi[axis] = mid;
    secondLo[axis] = mid;
    if (eyeCell[axis] < double(mid * metaCellSize)) {
        walkMetaCells(lo, firstHi, metaCellSize, eyeCell, visitor);
        walkMetaCells(secondLo, hi, metaCellSize, eyeCell, visitor);
    } else {
        walkMetaCells(secondLo, hi, metaCellSize, eyeCell, visitor);
        walkMetaCells(lo, firstHi, metaCellSize, eyeCell, visitor);
    }
}

}  // namespace vdiso
