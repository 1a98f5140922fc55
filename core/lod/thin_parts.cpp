#include "core/lod/thin_parts.h"

#include <algorithm>
#include <cmath>

#include <glm/geometric.hpp>

#include "core/brick_layout.h"
#include "core/kernel/iso.h"
#include "core/scalar_type.h"
#include "core/trees/sub_blocks.h"

namespace vdiso {

namespace {

// The coarse brick's samples, by cell corner (ghosts included: -1 .. cells + 1 on each axis).
template <class T>
struct CoarseSamples {
    const T* s;
    int side;
    double at(int x, int y, int z) const { return double(rangeValue(s[BrickLayout::cornerIndex(side, x, y, z)])); }
};

// The unit direction of largest |curvature| of the given sign at corner (x, y, z): the eigenvector
// of the central-difference Hessian (in world units) whose eigenvalue is most negative (sign -1:
// a peak) or most positive (+1: a trough), if it is kPlateCurvature times any other's; else zero.
constexpr double kPlateCurvature = 2.0;
template <class T>
glm::dvec3 acrossPart(const CoarseSamples<T>& c, int x, int y, int z, const glm::dvec3& h, double sign) {
    double H[3][3];
    const int o[3] = {x, y, z};
    auto sample = [&](int dx, int dy, int dz) { return c.at(o[0] + dx, o[1] + dy, o[2] + dz); };
    const double centre = sample(0, 0, 0);
    for (int a = 0; a < 3; ++a) {
        int d[3] = {0, 0, 0};
        d[a] = 1;
        H[a][a] = (sample(d[0], d[1], d[2]) - 2 * centre + sample(-d[0], -d[1], -d[2])) / (h[a] * h[a]);
        for (int b = a + 1; b < 3; ++b) {
            int e[3] = {0, 0, 0};
            e[a] = 1;
            e[b] = 1;
            int f[3] = {0, 0, 0};
            f[a] = 1;
            f[b] = -1;
            const double mixed = (sample(e[0], e[1], e[2]) + sample(-e[0], -e[1], -e[2]) - sample(f[0], f[1], f[2]) -
                                  sample(-f[0], -f[1], -f[2])) /
                                 (4 * h[a] * h[b]);
            H[a][b] = H[b][a] = mixed;
        }
    }
    // Cyclic Jacobi rotations: H = V diag(H) V^T, the eigenvectors in V's columns.
    double V[3][3] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
    for (int sweep = 0; sweep < 12; ++sweep)
        for (int p = 0; p < 2; ++p)
            for (int q = p + 1; q < 3; ++q) {
                if (!(std::abs(H[p][q]) > 1e-12 * (std::abs(H[p][p]) + std::abs(H[q][q])))) continue;
                // tan of the angle that zeroes H[p][q], the smaller root (Numerical Recipes' form).
                const double theta = (H[q][q] - H[p][p]) / (2 * H[p][q]);
                const double t = (theta >= 0 ? 1.0 : -1.0) / (std::abs(theta) + std::sqrt(theta * theta + 1));
                const double cosine = 1 / std::sqrt(t * t + 1), sine = t * cosine;
                for (int k = 0; k < 3; ++k) {  // H <- H J
                    const double hp = H[k][p], hq = H[k][q];
                    H[k][p] = cosine * hp - sine * hq;
                    H[k][q] = sine * hp + cosine * hq;
                }
                for (int k = 0; k < 3; ++k) {  // H <- J^T H
                    const double hp = H[p][k], hq = H[q][k];
                    H[p][k] = cosine * hp - sine * hq;
                    H[q][k] = sine * hp + cosine * hq;
                }
                for (int k = 0; k < 3; ++k) {  // V <- V J
                    const double vp = V[k][p], vq = V[k][q];
                    V[k][p] = cosine * vp - sine * vq;
                    V[k][q] = sine * vp + cosine * vq;
                }
            }
    // The column whose eigenvalue is most negative (a peak) or most positive (a trough), when
    // it stands out: a plate curves across far more than along itself. A blob, which curves
    // alike every way, has no such direction.
    int best = 0;
    for (int k = 1; k < 3; ++k)
        if (sign * H[k][k] > sign * H[best][best]) best = k;
    for (int k = 0; k < 3; ++k)
        if (k != best && std::abs(H[k][k]) * kPlateCurvature > std::abs(H[best][best])) return glm::dvec3(0.0);
    const glm::dvec3 v(V[0][best], V[1][best], V[2][best]);
    return std::isfinite(v.x + v.y + v.z) ? v : glm::dvec3(0.0);
}

// Whether corner (x, y, z) is a ridge (sign -1) or a valley (+1) across a part: along the
// lattice direction (of the 13) in which it stands out most from its two neighbours, it is at
// least as high (low) as both, by at least kRidgeRise of its rise above (depth below) `other`
// (the box's other extreme). A thick part's edge is a slope: no direction makes it stand out.
constexpr double kRidgeRise = 0.1;
constexpr double kLeastFacing = 0.25;  // cosine
template <class T>
bool isRidge(const CoarseSamples<T>& c, int x, int y, int z, double sign, double other) {
    static constexpr int kDirections[13][3] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {1, 1, 0}, {1, -1, 0},
                                               {1, 0, 1}, {1, 0, -1}, {0, 1, 1}, {0, 1, -1}, {1, 1, 1},
                                               {1, 1, -1}, {1, -1, 1}, {-1, 1, 1}};
    const double v = -sign * c.at(x, y, z);
    double best = -INFINITY;
    bool ridge = false;
    for (const int* d : kDirections) {
        const double before = -sign * c.at(x - d[0], y - d[1], z - d[2]), after = -sign * c.at(x + d[0], y + d[1], z + d[2]);
        const double rise = v - 0.5 * (before + after);
        if (rise > best) {
            best = rise;
            ridge = v >= before && v >= after;
        }
    }
    return ridge && best >= kRidgeRise * (v + sign * other);
}

// Where the coarse brick's cell corners are in the world.
struct CornerPlace {
    glm::dvec3 first, spacing;  // corner (0, 0, 0), and the level's spacing
    glm::dvec3 operator()(int x, int y, int z) const { return first + glm::dvec3(x, y, z) * spacing; }
};

// The corners of a part lost in the coarse corners [lo, hi] (each inclusive), a peak (sign -1)
// or a trough (+1) whose samples there run from `least` to `most`, that become points: on the
// lost side of the isovalue, at least halfway from the box's other extreme towards the part,
// and a ridge (or a valley) across it.
template <class T>
void findRidges(const CoarseSamples<T>& c, const LostPart& part, double iso, std::vector<std::array<int16_t, 3>>& corners) {
    const double halfway = 0.5 * (part.least + part.most), sign = part.sign;
    for (int z = part.lo[2]; z <= part.hi[2]; ++z)
        for (int y = part.lo[1]; y <= part.hi[1]; ++y)
            for (int x = part.lo[0]; x <= part.hi[0]; ++x) {
                const double v = c.at(x, y, z);
                if (sign < 0 ? (v < halfway || v > iso) : (v > halfway || v <= iso)) continue;
                if (!isRidge(c, x, y, z, sign, sign < 0 ? part.least : part.most)) continue;
                corners.push_back({int16_t(x), int16_t(y), int16_t(z)});
            }
}

// Appends the points of a part's ridge corners that `wanted` takes, each normal across the part
// and turned to the eye.
template <class T>
void appendRidgePoints(const CoarseSamples<T>& c, const CornerPlace& place, const LostPart& part, const glm::dvec3& eye,
                       PointSet& out, const std::function<bool(const glm::dvec3&)>& wanted) {
    for (const std::array<int16_t, 3>& r : part.ridges->corners) {
        const glm::dvec3 p = place(r[0], r[1], r[2]);
        if (wanted && !wanted(p)) continue;
        glm::dvec3 n = acrossPart(c, r[0], r[1], r[2], place.spacing, part.sign);
        const glm::dvec3 toEye = glm::normalize(eye - p);
        if (n == glm::dvec3(0.0)) n = toEye;
        if (glm::dot(n, toEye) < 0) n = -n;
        // Turned to within 75 degrees of the eye: the coarse samples give a thin part's facing
        // only roughly, and one seen edge on would shade black where the full surface shows its
        // face.
        const double facing = glm::dot(n, toEye);
        if (facing < kLeastFacing) n = glm::normalize(n + toEye * ((kLeastFacing - facing) / (1.0 - kLeastFacing)));
        out.positions.push_back(glm::vec3(p));
        out.normals.push_back(glm::vec3(n));
    }
}

}  // namespace

std::vector<LostPart> findLostParts(const BrickSource& coarse, int64_t brick, const void* samples, const BrickSource& fine,
                                    int levelsBetween, double iso) {
    const BrickLayout& cl = coarse.layout();
    const BrickLayout& fl = fine.layout();
    const Dims3 cc = cl.brickCoord(brick);
    const int64_t ratio = int64_t(1) << levelsBetween;  // fine cells per coarse cell
    int cells[3];
    int64_t f0[3], f1[3];  // the fine bricks under the coarse one, [f0, f1) per axis
    for (int k = 0; k < 3; ++k) {
        cells[k] = cl.cellsOnAxis(k, cc[k]);
        f0[k] = cc[k] * cl.brickSize * ratio / fl.brickSize;
        f1[k] = std::min<int64_t>(fl.brickCounts[k],
                                  ((cc[k] * cl.brickSize + cells[k]) * ratio + fl.brickSize - 1) / fl.brickSize);
    }
    const int C = subBlockCells(fl.brickSize);
    std::vector<LostPart> parts;
    visitScalarType(coarse.volume().type, [&](auto zero) {
        using T = decltype(zero);
        const CoarseSamples<T> c{static_cast<const T*>(samples), cl.side()};
        for (int64_t fz = f0[2]; fz < f1[2]; ++fz)
            for (int64_t fy = f0[1]; fy < f1[1]; ++fy)
                for (int64_t fx = f0[0]; fx < f1[0]; ++fx) {
                    const int64_t id = fl.brickId(fx, fy, fz);
                    const BrickRange whole = fine.brickRanges()[size_t(id)];
                    if (!crossesClearly(whole, iso)) continue;
                    const std::span<const SubBlockCode> codes = fine.subBlockCodesOf(id);
                    const int64_t fc[3] = {fx, fy, fz};
                    const int blocks = codes.empty() ? 1 : kSubBlocksPerAxis;
                    const int size = codes.empty() ? fl.brickSize : C;
                    // The isovalue in the codes' steps (255 over the brick's range): a code far
                    // from it is not decoded.
                    const double span = double(whole.maxValue) - double(whole.minValue);
                    const double isoStep = span > 0 ? (iso - double(whole.minValue)) / span * 255.0 : 0.0;
                    for (int b = 0; b < blocks * blocks * blocks; ++b) {
                        if (!codes.empty() && (codes[size_t(b)].lo > isoStep + 1 || codes[size_t(b)].hi < isoStep - 1))
                            continue;
                        const BrickRange r = codes.empty() ? whole : decodeSubBlockRange(codes[size_t(b)], whole);
                        if (!crossesClearly(r, iso)) continue;
                        const int at[3] = {b % blocks, b / blocks % blocks, b / (blocks * blocks)};
                        int lo[3], hi[3];  // the coarse corners of the cells meeting the box
                        bool inside = true;
                        for (int k = 0; k < 3; ++k) {
                            const int64_t first = fc[k] * fl.brickSize + int64_t(at[k]) * size;
                            const int64_t last =
                                std::min<int64_t>(first + size, fc[k] * fl.brickSize + fl.cellsOnAxis(k, fc[k]));
                            const int64_t origin = cc[k] * cl.brickSize;
                            // first and last are not negative: shifts are the divisions by ratio.
                            lo[k] = int(std::clamp<int64_t>((first >> levelsBetween) - origin, 0, cells[k]));
                            hi[k] = int(std::clamp<int64_t>(((last + ratio - 1) >> levelsBetween) - origin, 0, cells[k]));
                            inside = inside && first < last && lo[k] < hi[k];
                        }
                        if (!inside) continue;
                        // A peak (the fine samples' reach above the isovalue) or a trough the
                        // coarse level lost, or kept less than kKeptReach of: the part is gone
                        // here, or in strips. The coarse corners are ranged in the samples' own
                        // type a row at a time, and the box is left as soon as they reach far
                        // enough both ways (most boxes, where the coarse surface kept the part:
                        // ranging every corner was most of a distant CT frame's thin-part work).
                        const double fineUp = double(r.maxValue) - iso, fineDown = iso - double(r.minValue);
                        T lowest = rangeValue(c.s[BrickLayout::cornerIndex(c.side, lo[0], lo[1], lo[2])]);
                        T highest = lowest;
                        bool kept = false;
                        for (int z = lo[2]; z <= hi[2] && !kept; ++z)
                            for (int y = lo[1]; y <= hi[1] && !kept; ++y) {
                                const T* row = c.s + BrickLayout::cornerIndex(c.side, 0, y, z);
                                for (int x = lo[0]; x <= hi[0]; ++x) {
                                    lowest = std::min(lowest, rangeValue(row[x]));
                                    highest = std::max(highest, rangeValue(row[x]));
                                }
                                kept = !(double(highest) - iso < kKeptReach * fineUp) &&
                                       !(iso - double(lowest) < kKeptReach * fineDown);
                            }
                        if (kept) continue;  // the sign below would be 0
                        const double least = double(lowest), most = double(highest);
                        const double sign = most - iso < kKeptReach * fineUp ? -1.0
                                            : iso - least < kKeptReach * fineDown ? 1.0
                                                                                 : 0.0;
                        if (sign == 0.0) continue;
                        parts.push_back({{lo[0], lo[1], lo[2]}, {hi[0], hi[1], hi[2]}, sign, least, most});
                    }
                }
    });
    return parts;
}

void appendLostPartPoints(const BrickSource& coarse, int64_t brick, const void* samples, std::span<const LostPart> parts,
                          double iso, const glm::dvec3& eye, PointSet& out,
                          const std::function<bool(const glm::dvec3&)>& wanted,
                          const std::function<bool(const glm::dvec3&, const glm::dvec3&)>& shows) {
    if (parts.empty()) return;
    const BrickLayout& cl = coarse.layout();
    const VolumeInfo& volume = coarse.volume();
    const Dims3 cc = cl.brickCoord(brick);
    const CornerPlace place{volume.origin + glm::dvec3(cc[0], cc[1], cc[2]) * double(cl.brickSize) * volume.spacing,
                            volume.spacing};
    visitScalarType(volume.type, [&](auto zero) {
        using T = decltype(zero);
        const CoarseSamples<T> c{static_cast<const T*>(samples), cl.side()};
        for (const LostPart& p : parts) {
            if (shows && !shows(place(p.lo[0], p.lo[1], p.lo[2]), place(p.hi[0], p.hi[1], p.hi[2]))) continue;
            std::call_once(p.ridges->found, [&] {
                p.ridges->corners.clear();  // a try that threw (no memory) left part of them
                findRidges(c, p, iso, p.ridges->corners);
            });
            appendRidgePoints(c, place, p, eye, out, wanted);
        }
    });
}

}  // namespace vdiso
