// Taubin's lambda|mu smoothing (Taubin 1995, "A signal processing approach to fair surface
// design"): each iteration is a shrinking Laplacian step (lambda = 0.5) and an inflating one
// (mu = 1 / (kPassBand - 1 / lambda), kPassBand = 0.1), so the surface loses its high
// frequencies (the voxel staircase) without the shrinkage plain Laplacian smoothing causes.
//
// The Laplacian is the umbrella operator: the mean of a vertex's edge neighbours minus the
// vertex. A vertex on an open edge (one triangle: where the volume's faces cut the surface)
// stays where it is, so the cut stays on the volume's faces (sliding along the border would
// take a vertex where the border turns a corner of the box off both faces). Each vertex sums its neighbours in increasing index order, and normals sum triangles in
// their order: the same neighbourhood gives bit-identical results whatever else a mesh holds,
// which the out-of-core smoothing (core/mesh_post/mesh_slabs.h) relies on to match smoothing all at once.
#pragma once

#include <cstdint>
#include <span>

#include <glm/vec3.hpp>

namespace vdiso {

// Smooths `positions` in place over the triangles `indices` (3 per triangle, indices into
// positions). Vertices no triangle uses do not move. A vertex's result after `iterations`
// depends only on the triangles within 2 * iterations + 1 edges of it.
void smoothTaubin(std::span<glm::vec3> positions, std::span<const uint32_t> indices, int iterations);

// Area-weighted vertex normals of the triangles, written for the vertices in
// [first, first + count) only; a vertex whose triangles have no area keeps its normal.
// Depends only on the triangles using each vertex.
void triangleNormals(std::span<const glm::vec3> positions, std::span<const uint32_t> indices,
                     std::span<glm::vec3> normals, uint32_t first, uint32_t count);

}  // namespace vdiso
