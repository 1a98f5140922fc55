// Orientation: volume space (origin + index * spacing, axis-aligned: where vdiso extracts, culls
// and renders) against physical space (the patient's LPS coordinates the scanner gave,
// core/volume.h), and the checks and conversions every reader of an oriented format shares.
//
// A volume's direction matrix D (columns: the unit LPS directions of the i, j, k axes) places
// sample (i,j,k) at origin + D ((i,j,k) * spacing), so a point p of volume space is at
//   physical(p) = origin + D (p - origin),
// the same origin in both spaces. D is usually a rotation, often with a flip (NIfTI files stored
// radiologically, DICOM stacks read feet first) and rarely a shear: a normal then maps by the
// inverse transpose of D, renormalised, and a mirroring D (det < 0) reverses triangle winding.
// Pure functions: safe from any thread.
#pragma once

#include <string>

#include <glm/mat3x3.hpp>
#include <glm/vec3.hpp>

#include "core/mesh.h"
#include "core/volume.h"

namespace vdiso {

// "" when `direction` can place a volume: every entry finite, no column of zero length, and the
// columns, normalised, span space (|det| above 1e-6, far from any real scanner's shear); else
// what is wrong, in words, for a reader to prefix with its file's name and field.
std::string directionProblem(const glm::dmat3& direction);

// The columns made unit length (DICOM and MetaImage cosines written with few digits). Columns of
// zero length stay as they are (directionProblem refuses them).
glm::dmat3 normalizedColumns(const glm::dmat3& m);

// A matrix whose columns are the axes' whole steps, direction times spacing (NRRD's space
// directions, NIfTI's sform), as spacing (the columns' lengths) and unit directions.
void splitScaledColumns(const glm::dmat3& scaled, glm::dmat3& direction, glm::dvec3& spacing);

// RAS coordinates (NIfTI, NRRD's right-anterior-superior) to LPS and back: x and y change sign.
// The map is its own inverse. A direction matrix converts as rasToLps * D.
inline const glm::dmat3 kRasToLps{-1.0, 0.0, 0.0, 0.0, -1.0, 0.0, 0.0, 0.0, 1.0};

// For each of the i, j, k axes, the letter of the patient side its direction points to most
// nearly: L or R (LPS +x or -x), P or A (+y, -y), S or I (+z, -z). "RAS" for a grid whose i
// runs to the patient's right, j to the front and k up.
std::string axisSidesCode(const glm::dmat3& direction);

// An affine map of meshes: a position p goes to linear * p + offset, a normal n to the inverse
// transpose of linear times n, renormalised (linear itself when orthonormal). When linear mirrors
// (det < 0), the winding of every triangle must be reversed so that its corners stay
// counter-clockwise seen from the side its normal points to; transformMesh does.
struct SpaceTransform {
    glm::dmat3 linear{1.0};
    glm::dvec3 offset{0.0};

    bool isIdentity() const { return linear == glm::dmat3(1.0) && offset == glm::dvec3(0.0); }
    bool mirrors() const;
};

// Volume space to physical space: p -> origin + direction (p - origin). The identity for a
// volume without orientation.
SpaceTransform volumeToPhysical(const VolumeInfo& volume);

// Applies `t` in place to the positions and normals, and reverses the triangles' winding when
// `t` mirrors. Indices may refer to vertices handed on before (firstVertex > 0): only their
// order within each triangle changes.
void transformMesh(const SpaceTransform& t, TriangleMesh& mesh);
void transformPoints(const SpaceTransform& t, PointSet& points);

}  // namespace vdiso
