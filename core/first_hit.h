// Where a pixel's ray first meets the isosurface inside one brick: the position and normal of
// a SAGE point (§3.3), which stands for the triangles of a sub-pixel box and must shade as they
// would.
//
// The ray is origin + t * direction (world units), t in [tEnter, tExit], a segment that lies
// within the kernel's brick. It is marched through the trilinear interpolant in quarter-sample
// steps; the first sign change is refined by linear interpolation. The normal is minus the
// gradient there: the kernel's central differences at the cell's corners, interpolated, which
// is how vertex normals are estimated too. Returns false when the segment does not cross.
#pragma once

#include <algorithm>
#include <cmath>

#include <glm/geometric.hpp>

#include "core/brick_kernel.h"

namespace vdiso {

template <class T>
bool firstHit(const BrickKernel<T>& kernel, const glm::dvec3& origin, const glm::dvec3& direction,
              double tEnter, double tExit, glm::vec3& position, glm::vec3& normal) {
    const VolumeInfo& volume = kernel.volume();
    const T* s = kernel.s;
    const int side = kernel.side;
    const size_t dy = size_t(side), dz = size_t(side) * side;
    // Sample-array coordinates of a world point (ghost offset included).
    auto toLocal = [&](const glm::dvec3& w) {
        glm::dvec3 l;
        for (int a = 0; a < 3; ++a)
            l[a] = (w[a] - volume.origin[a]) / volume.spacing[a] - double(kernel.corner0[a]) + kGhostBefore;
        return l;
    };
    auto field = [&](const glm::dvec3& l) {
        int i[3];
        double f[3];
        for (int a = 0; a < 3; ++a) {
            const double x = std::clamp(l[a], 0.0, double(side - 1) - 1e-9);
            i[a] = std::min(int(x), side - 2);
            f[a] = x - i[a];
        }
        const size_t base = (size_t(i[2]) * side + size_t(i[1])) * side + size_t(i[0]);
        auto at = [&](size_t o) { return double(s[base + o]); };
        const double x00 = at(0) + f[0] * (at(1) - at(0));
        const double x10 = at(dy) + f[0] * (at(dy + 1) - at(dy));
        const double x01 = at(dz) + f[0] * (at(dz + 1) - at(dz));
        const double x11 = at(dz + dy) + f[0] * (at(dz + dy + 1) - at(dz + dy));
        const double y0 = x00 + f[1] * (x10 - x00), y1 = x01 + f[1] * (x11 - x01);
        return y0 + f[2] * (y1 - y0);
    };
    const double samples = glm::length(toLocal(origin + direction * tExit) - toLocal(origin + direction * tEnter));
    const int steps = std::max(2, int(std::ceil(samples * 4)));
    double tPrevious = tEnter;
    double previous = field(toLocal(origin + direction * tEnter));
    for (int k = 1; k <= steps; ++k) {
        const double t = tEnter + (tExit - tEnter) * k / steps;
        const double value = field(toLocal(origin + direction * t));
        if (isAbove(previous, kernel.iso) != isAbove(value, kernel.iso)) {
            const double u = crossingFraction(previous, value, kernel.iso);
            const glm::dvec3 w = origin + direction * (tPrevious + u * (t - tPrevious));
            const glm::dvec3 l = toLocal(w);
            int i[3];
            double f[3];
            for (int a = 0; a < 3; ++a) {
                const double x = std::clamp(l[a], 1.0, double(side - 2) - 1e-9);
                i[a] = std::min(int(x), side - 3);
                f[a] = x - i[a];
            }
            glm::dvec3 gradient(0.0);
            for (int corner = 0; corner < 8; ++corner) {
                const int o[3] = {corner & 1, (corner >> 1) & 1, (corner >> 2) & 1};
                const size_t at = (size_t(i[2] + o[2]) * side + size_t(i[1] + o[1])) * side + size_t(i[0] + o[0]);
                const double weight = (o[0] ? f[0] : 1 - f[0]) * (o[1] ? f[1] : 1 - f[1]) * (o[2] ? f[2] : 1 - f[2]);
                gradient += weight * kernel.gradientAt(at);
            }
            const double length = glm::length(gradient);
            position = glm::vec3(w);
            normal = length > 0 ? glm::vec3(-gradient / length) : glm::vec3(0.0f);
            return true;
        }
        previous = value;
        tPrevious = t;
    }
    return false;
}

}  // namespace vdiso
