// Shapes of the generated head (core/synth/synth.h), measured in voxels so that transitions have the
// same width at every size: smooth material weights, ellipsoids and their spans along a row.
// Internal to the generators (synth_*.cpp).
#pragma once

#include <algorithm>
#include <cmath>

#include <glm/vec3.hpp>

namespace vdiso::synth_detail {


inline float sq(float v) {
    return v * v;
}

// Material transitions are a smoothstep of signed distance across this many voxels either side
// of the surface: wide enough that isosurfaces interpolate smoothly instead of following the
// voxel staircase, narrow enough to keep thin shells (the skull) at full value.
constexpr float kEdgeHalfWidth = 1.0f;

// 1 inside (d <= -kEdgeHalfWidth), 0 outside (d >= kEdgeHalfWidth).
inline float insideWeight(float d) {
    const float t = std::min(std::max(0.5f - d * (0.5f / kEdgeHalfWidth), 0.0f), 1.0f);
    return t * t * (3.0f - 2.0f * t);
}

inline float lerp(float a, float b, float t) {
    return a + (b - a) * t;
}

// Polynomial smooth minimum: a union of two distance fields without a crease where they meet.
// Never below min(a, b) - k / 4.
inline float smoothUnion(float a, float b, float k) {
    const float h = std::max(k - std::abs(a - b), 0.0f) / k;
    return std::min(a, b) - h * h * k * 0.25f;
}

constexpr float kNoCap = -1e30f;

// An axis-aligned ellipsoid in voxel coordinates. An infinite radius makes it an elliptic
// cylinder along that axis. `cap` optionally cuts it with a half-space normal to y or z.
struct Shape {
    glm::vec3 center{0.0f};
    glm::vec3 radii{1.0f};
    int capAxis = 0;  // 0: none, 1: y, 2: z
    float capLimit = 0.0f;
    float capSign = 1.0f;  // inside where capSign * (coord - capLimit) < 0

    float cap(float y, float z) const {
        if (capAxis == 0) return kNoCap;
        return capSign * ((capAxis == 1 ? y : z) - capLimit);
    }
};

struct Span {
    int begin = 0;
    int end = 0;
};

inline Span intersect(Span a, Span b) {
    return {std::max(a.begin, b.begin), std::min(a.end, b.end)};
}

inline Span hull(Span a, Span b) {
    if (a.begin >= a.end) return b;
    if (b.begin >= b.end) return a;
    return {std::min(a.begin, b.begin), std::max(a.end, b.end)};
}

// A shape restricted to one row: y and z are fixed, so what is left is a function of x.
//
// The distance is Quilez's ellipsoid estimate k0 (k0 - 1) / k1 with k0 = |q / r|, k1 = |q / r^2|:
// exact on the surface and close within the few voxels the smoothstep looks at. At the very
// centre it is 0 / 0; elsewhere inside it is never shallower than (k0 - 1) * rmin, so taking the
// minimum with that fixes the centre and changes nothing else.
struct RowShape {
    float cx = 0.0f;
    float invRx = 0.0f;
    float k0Rest = 0.0f;  // |q / r|^2 without its x term
    float k1Rest = 0.0f;  // |q / r^2|^2 without its x term
    float rmin = 1.0f;
    float cap = kNoCap;
    Span span;  // where the distance can be below the margin it was built with

    float distance(float x) const {
        const float a = (x - cx) * invRx;
        const float k0 = std::sqrt(a * a + k0Rest);
        const float k1 = std::sqrt(sq(a * invRx) + k1Rest);
        const float estimate = k0 * (k0 - 1.0f) / std::max(k1, 1e-30f);
        const float d = k0 < 1.0f ? std::min(estimate, (k0 - 1.0f) * rmin) : estimate;
        return std::max(d, cap);
    }
};

inline RowShape rowShape(const Shape& s, float y, float z, float margin, int nx) {
    RowShape r;
    r.cx = s.center.x;
    r.invRx = 1.0f / s.radii.x;
    const float qy = (y - s.center.y) / s.radii.y;
    const float qz = (z - s.center.z) / s.radii.z;
    r.k0Rest = qy * qy + qz * qz;
    r.k1Rest = sq(qy / s.radii.y) + sq(qz / s.radii.z);
    r.rmin = std::min({s.radii.x, s.radii.y, s.radii.z});
    r.cap = s.cap(y, z);
    if (r.cap >= margin) return r;
    // Outside, the estimate is at least (k0 - 1) * rmin, so d < margin needs k0 < limit.
    const float limit = 1.0f + margin / r.rmin;
    const float t = limit * limit - r.k0Rest;
    if (t <= 0.0f) return r;
    const float half = s.radii.x * std::sqrt(t);
    r.span.begin = std::clamp(int(std::floor(r.cx - half)), 0, nx);
    r.span.end = std::clamp(int(std::ceil(r.cx + half)) + 1, 0, nx);
    return r;
}


}  // namespace vdiso::synth_detail
