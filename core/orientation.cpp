#include "core/orientation.h"

#include <cmath>
#include <utility>

#include <glm/geometric.hpp>
#include <glm/matrix.hpp>

namespace vdiso {

namespace {

// Below this |det| of the normalised columns, two axes are within about 1e-6 rad of each other
// or of a plane: no scanner writes that; a file that does is damaged.
constexpr double kMinUnitDeterminant = 1e-6;

// The inverse transpose, computed once per mesh piece: how normals follow a linear map.
glm::dmat3 normalMatrix(const glm::dmat3& linear) { return glm::transpose(glm::inverse(linear)); }

// A normal through the normal matrix, unit again; a zero normal (a flat gradient) stays zero.
glm::vec3 mappedNormal(const glm::dmat3& normals, glm::vec3 n) {
    const glm::dvec3 m = normals * glm::dvec3(n);
    const double length = glm::length(m);
    return length > 0.0 ? glm::vec3(m / length) : glm::vec3(0.0f);
}

}  // namespace

std::string directionProblem(const glm::dmat3& direction) {
    for (int c = 0; c < 3; ++c)
        for (int r = 0; r < 3; ++r)
            if (!std::isfinite(direction[c][r])) return "the direction matrix holds a value that is not finite";
    static const char* kAxis[3] = {"first", "second", "third"};
    for (int c = 0; c < 3; ++c)
        if (!(glm::length(direction[c]) > 0.0))
            return std::string("the direction of the ") + kAxis[c] + " axis is a zero vector";
    const double det = glm::determinant(normalizedColumns(direction));
    if (!(std::abs(det) > kMinUnitDeterminant))
        return "the directions of the three axes lie in one plane (the direction matrix is singular)";
    return "";
}

glm::dmat3 normalizedColumns(const glm::dmat3& m) {
    glm::dmat3 out = m;
    for (int c = 0; c < 3; ++c) {
        const double length = glm::length(m[c]);
        if (length > 0.0) out[c] = m[c] / length;
    }
    return out;
}

void splitScaledColumns(const glm::dmat3& scaled, glm::dmat3& direction, glm::dvec3& spacing) {
    for (int c = 0; c < 3; ++c) spacing[c] = glm::length(scaled[c]);
    direction = normalizedColumns(scaled);
}

std::string axisSidesCode(const glm::dmat3& direction) {
    static const char kPositive[3] = {'L', 'P', 'S'}, kNegative[3] = {'R', 'A', 'I'};
    std::string code;
    for (int c = 0; c < 3; ++c) {
        int most = 0;
        for (int r = 1; r < 3; ++r)
            if (std::abs(direction[c][r]) > std::abs(direction[c][most])) most = r;
        code += direction[c][most] >= 0.0 ? kPositive[most] : kNegative[most];
    }
    return code;
}

bool SpaceTransform::mirrors() const { return glm::determinant(linear) < 0.0; }

SpaceTransform volumeToPhysical(const VolumeInfo& volume) {
    if (!volume.hasOrientation) return {};
    SpaceTransform t;
    t.linear = volume.direction;
    t.offset = volume.origin - volume.direction * volume.origin;
    return t;
}

void transformMesh(const SpaceTransform& t, TriangleMesh& mesh) {
    const glm::dmat3 normals = normalMatrix(t.linear);
    for (glm::vec3& p : mesh.positions) p = glm::vec3(t.linear * glm::dvec3(p) + t.offset);
    for (glm::vec3& n : mesh.normals) n = mappedNormal(normals, n);
    if (t.mirrors())
        for (size_t i = 0; i + 2 < mesh.indices.size(); i += 3) std::swap(mesh.indices[i + 1], mesh.indices[i + 2]);
}

void transformPoints(const SpaceTransform& t, PointSet& points) {
    const glm::dmat3 normals = normalMatrix(t.linear);
    for (glm::vec3& p : points.positions) p = glm::vec3(t.linear * glm::dvec3(p) + t.offset);
    for (glm::vec3& n : points.normals) n = mappedNormal(normals, n);
}

}  // namespace vdiso
