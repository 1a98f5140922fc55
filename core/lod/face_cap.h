// Closing a brick's surface on one of its faces: how the seams between levels of detail are
// kept out of the picture (docs/design.md, "One frame, view-dependent"; core/lod/view_levels.h).
//
// Where a brick meets a neighbour extracted at another level, their surfaces meet the shared
// face along two different curves (each level's marching squares on its own samples), and the
// sliver of face between the curves is a crack through which the background could show. Each
// side caps the face: the part of the face inside its surface (samples above the isovalue),
// bounded by its curve, is appended as triangles. The sliver is inside one level's surface and
// outside the other's, so it lies in one of the two caps. A cap lies inside the solid its
// surface bounds, so everywhere but through a crack the surface in front hides it: it is drawn,
// never scan-converted into the occlusion pyramid (the pixels it could add are the crack's, at
// most the lod-error wide). Vertices take the field's normals (minus its gradient), so a cap
// seen through a crack is shaded like the surface around it.
//
// Only the band of face cells the curve crosses is capped: the inside polygon of each walks the
// square's corners in order, taking each inside corner and each edge crossing. The slivers lie
// within about a cell of the curves, and a whole cap (every inside cell) showed through the
// volume's own open faces where a solid is cut by them (turbulence: 820 more pixels of the
// wrong colour at 4 px), which the band does not.
#pragma once

#include <cmath>
#include <cstdint>

#include <glm/geometric.hpp>
#include <glm/vec3.hpp>

#include "core/kernel/brick_kernel.h"
#include "core/kernel/iso.h"
#include "core/mesh.h"

namespace vdiso {

// Appends to `mesh` the cap band of the brick's face on `axis`, at its low end or its high
// (`upper`) end.
template <class T>
void appendFaceCap(const BrickKernel<T>& k, int axis, bool upper, TriangleMesh& mesh) {
    const int u = (axis + 1) % 3, v = (axis + 2) % 3;
    const int plane = upper ? k.cells[axis] : 0;
    glm::dvec3 outward(0.0);
    outward[axis] = upper ? 1.0 : -1.0;
    const glm::dvec3& spacing = k.volume().spacing;
    const glm::dvec3 origin = k.volume().origin + glm::dvec3(k.corner0[0], k.corner0[1], k.corner0[2]) * spacing;

    auto local = [&](double pu, double pv) {
        glm::dvec3 p;
        p[axis] = plane;
        p[u] = pu;
        p[v] = pv;
        return p;
    };
    auto index = [&](int cu, int cv) {
        int c[3];
        c[axis] = plane;
        c[u] = cu;
        c[v] = cv;
        return k.sampleIndex(c[0], c[1], c[2]);
    };
    auto addVertex = [&](const glm::dvec3& p, const glm::vec3& normal) {
        const uint32_t vertex = mesh.nextVertex();
        mesh.positions.push_back(glm::vec3(origin + p * spacing));
        mesh.normals.push_back(normal);
        return vertex;
    };
    auto cornerNormal = [&](size_t i) {
        const glm::dvec3 g = k.gradientAt(i);
        const double length = glm::length(g);
        return glm::vec3(length > 0 && std::isfinite(length) ? -g / length : outward);
    };
    // A fan facing `outward` (counter-clockwise seen from the neighbour's side).
    // (u, v, axis) is right-handed: the square's corner order turns counter-clockwise about +axis.
    const bool flip = !upper;
    auto addFan = [&](const uint32_t* vertices, int count) {
        for (int t = 2; t < count; ++t) {
            const uint32_t a = vertices[0], b = vertices[t - 1], c = vertices[t];
            mesh.indices.insert(mesh.indices.end(), {a, flip ? c : b, flip ? b : c});
        }
    };

    // Corners of a face cell in order around it, as (du, dv).
    static constexpr int kSquare[4][2] = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
    for (int cv = 0; cv < k.cells[v]; ++cv)
        for (int cu = 0; cu < k.cells[u]; ++cu) {
            bool inside[4];
            size_t at[4];
            int insideCount = 0;
            for (int q = 0; q < 4; ++q) {
                at[q] = index(cu + kSquare[q][0], cv + kSquare[q][1]);
                inside[q] = isAbove(double(k.s[at[q]]), k.iso);
                insideCount += inside[q];
            }
            if (insideCount == 0 || insideCount == 4) continue;  // the band only
            uint32_t polygon[8];
            int n = 0;
            for (int q = 0; q < 4; ++q) {
                const int r = (q + 1) % 4;
                if (inside[q])
                    polygon[n++] = addVertex(local(cu + kSquare[q][0], cv + kSquare[q][1]), cornerNormal(at[q]));
                if (inside[q] != inside[r]) {
                    const double t = crossingFraction(double(k.s[at[q]]), double(k.s[at[r]]), k.iso);
                    const glm::dvec3 p = glm::mix(local(cu + kSquare[q][0], cv + kSquare[q][1]),
                                                  local(cu + kSquare[r][0], cv + kSquare[r][1]), t);
                    const glm::dvec3 g = glm::mix(k.gradientAt(at[q]), k.gradientAt(at[r]), t);
                    const double length = glm::length(g);
                    polygon[n++] = addVertex(p, glm::vec3(length > 0 && std::isfinite(length) ? -g / length : outward));
                }
            }
            addFan(polygon, n);
        }
}

}  // namespace vdiso
