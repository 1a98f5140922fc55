#include "core/synth.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <vector>

#include <glm/vec3.hpp>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

namespace vdiso {
namespace {

// ---- Hashing: every random number is a hash of (seed, integer position), never a stream, so a
// sample does not depend on which samples were generated before it.

constexpr uint64_t kGolden64 = 0x9E3779B97F4A7C15ull;
// Odd multipliers that spread lattice coordinates before mixing.
constexpr uint64_t kLatticeX = 0xD6E8FEB86659FD93ull;
constexpr uint64_t kLatticeY = 0xA0761D6478BD642Full;
constexpr uint64_t kLatticeZ = 0xE7037ED1A0B428DBull;

// SplitMix64's finaliser: a bijection whose output bits each depend on every input bit.
inline uint64_t mix64(uint64_t x) {
    x ^= x >> 30;
    x *= 0xBF58476D1CE4E5B9ull;
    x ^= x >> 27;
    x *= 0x94D049BB133111EBull;
    return x ^ (x >> 31);
}

inline uint64_t latticeKey(uint64_t key, int64_t y, int64_t z) {
    return key + uint64_t(y) * kLatticeY + uint64_t(z) * kLatticeZ;
}

inline uint64_t latticeHash(uint64_t rowKey, int64_t x) {
    return mix64(rowKey + uint64_t(x) * kLatticeX);
}

// A 32-bit finaliser (Wellons' lowbias32): cheap enough to run once per sample, and 32-bit
// multiplies vectorise where 64-bit ones do not.
inline uint32_t mix32(uint32_t x) {
    x ^= x >> 16;
    x *= 0x7FEB352Du;
    x ^= x >> 15;
    x *= 0x846CA68Bu;
    return x ^ (x >> 16);
}

// Uniform white noise in [-1, 1), one value per sample of the row.
void whiteNoiseRow(uint64_t rowKey, int nx, float* out) {
    const uint32_t key = uint32_t(mix64(rowKey));
    constexpr float kScale = 2.0f / 16777216.0f;
    for (int x = 0; x < nx; ++x)
        out[x] = float(mix32(key + uint32_t(x) * 0x9E3779B9u) >> 8) * kScale - 1.0f;
}

// ---- Shapes, measured in voxels so that transitions have the same width at every size.

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

RowShape rowShape(const Shape& s, float y, float z, float margin, int nx) {
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

// ---- The head.
//
// Normalised coordinates map each axis of the volume to [-1, 1], so the head fills the same
// fraction of any volume. +z is up (the neck leaves through the bottom face, z = -1), +y is the
// face (eye sockets, nose, jaw), x runs ear to ear.

// CT-like values. Noise amplitudes keep each material on its side of both isovalues.
constexpr float kAir = 30.0f, kAirNoise = 30.0f;
constexpr float kTissue = 1000.0f, kTissueNoise = 40.0f;
constexpr float kBrain = 1050.0f, kBrainNoise = 40.0f;
constexpr float kFluid = 350.0f, kFluidNoise = 30.0f;
constexpr float kBone = 1850.0f, kBoneNoise = 60.0f;

constexpr float kInf = std::numeric_limits<float>::infinity();

struct NormalisedShape {
    glm::vec3 center;
    glm::vec3 radii;
    int capAxis = 0;
    float capLimit = 0.0f;
    float capSign = 1.0f;
};

// The cranium is an egg: longer towards the back and flatter underneath.
constexpr glm::vec3 kCraniumCenter{0.0f, 0.0f, 0.12f};
constexpr float kCraniumRx = 0.70f;
constexpr float kCraniumRyFront = 0.78f, kCraniumRyBack = 0.84f;
constexpr float kCraniumRzTop = 0.78f, kCraniumRzBottom = 0.70f;

// Soft tissue merged into the cranium: neck (down through the bottom face), jaw, nose.
const NormalisedShape kNeck{{0.0f, -0.12f, 0.0f}, {0.34f, 0.36f, kInf}, 2, 0.12f, 1.0f};
const NormalisedShape kJaw{{0.0f, 0.30f, -0.55f}, {0.45f, 0.42f, 0.30f}};
const NormalisedShape kNose{{0.0f, 0.72f, -0.25f}, {0.07f, 0.14f, 0.15f}};
constexpr float kSkinBlend = 0.12f;  // smooth-union radius, in units of the smallest axis

// Holes through the skull (not through the skin): cylinders that stop at a half-space so they
// cut one side of the shell only.
const NormalisedShape kSkullHoles[] = {
    {{-0.27f, 0.0f, -0.02f}, {0.13f, kInf, 0.11f}, 1, 0.2f, -1.0f},  // right eye socket
    {{0.27f, 0.0f, -0.02f}, {0.13f, kInf, 0.11f}, 1, 0.2f, -1.0f},   // left eye socket
    {{0.0f, 0.0f, -0.30f}, {0.07f, kInf, 0.10f}, 1, 0.2f, -1.0f},    // nasal aperture
    {{0.0f, -0.15f, 0.0f}, {0.12f, 0.14f, kInf}, 2, 0.12f, 1.0f},    // foramen magnum
    {{-0.22f, 0.05f, 0.0f}, {0.04f, 0.04f, kInf}, 2, -0.2f, 1.0f},   // jugular foramina
    {{0.22f, 0.05f, 0.0f}, {0.04f, 0.04f, kInf}, 2, -0.2f, 1.0f},
};

// Dense bits inside the skull, so occlusion culling has something to hide.
const NormalisedShape kInnerBones[] = {
    {{-0.38f, -0.05f, -0.28f}, {0.12f, 0.07f, 0.06f}},  // petrous bones (inner ears)
    {{0.38f, -0.05f, -0.28f}, {0.12f, 0.07f, 0.06f}},
    {{0.0f, 0.12f, -0.36f}, {0.10f, 0.05f, 0.04f}},  // sella
};

// Fluid-filled ventricles in the brain: inner surfaces of the skin isovalue.
const NormalisedShape kVentricles[] = {
    {{-0.12f, -0.05f, 0.25f}, {0.06f, 0.28f, 0.12f}},
    {{0.12f, -0.05f, 0.25f}, {0.06f, 0.28f, 0.12f}},
};

// The spine rises through the neck towards the foramen magnum as a stack of vertebrae.
const NormalisedShape kSpine{{0.0f, -0.18f, 0.0f}, {0.07f, 0.07f, kInf}, 2, -0.62f, 1.0f};
constexpr float kVertebraPeriod = 0.09f, kDiscGap = 0.025f;

// The mandible: part of a shell inside the jaw, in front and low.
constexpr float kMandibleFront = 0.12f, kMandibleTop = -0.6f;

// Skull depth and thickness relative to the cranium's smallest radius, with a floor in voxels so
// that small volumes still have a shell that reaches full bone value.
constexpr float kSkullDepth = 0.05f, kSkullThickness = 0.055f;
constexpr float kMinSkullDepthVoxels = 2.5f, kMinSkullThicknessVoxels = 3.0f;

class HeadModel {
public:
    // Per-task buffers, one row long.
    struct Scratch {
        std::vector<float> noise, cranium, skin, bone;
        explicit Scratch(const HeadModel& m)
            : noise(size_t(m.mNx)),
              cranium(size_t(m.mNx)),
              skin(size_t(m.mNx)),
              bone(size_t(m.mNx)) {}
    };

    explicit HeadModel(const SynthParams& p) : mNx(int(p.dims[0])), mSeed(mix64(p.seed)) {
        for (int a = 0; a < 3; ++a) mScale[a] = 0.5f * float(p.dims[a] - 1);
        mUnit = std::min({mScale.x, mScale.y, mScale.z});
        const float cranium = std::min(
            {kCraniumRx * mScale.x, kCraniumRyFront * mScale.y, kCraniumRzBottom * mScale.z});
        mSkullDepth = std::max(kSkullDepth * cranium, kMinSkullDepthVoxels);
        mSkullThickness = std::max(kSkullThickness * cranium, kMinSkullThicknessVoxels);
        mSkinBlend = kSkinBlend * mUnit;
        mNeck = toVoxels(kNeck);
        mJaw = toVoxels(kJaw);
        mNose = toVoxels(kNose);
        for (const NormalisedShape& s : kSkullHoles) mHoles.push_back(toVoxels(s));
        for (const NormalisedShape& s : kInnerBones) mInnerBones.push_back(toVoxels(s));
        for (const NormalisedShape& s : kVentricles) mVentricles.push_back(toVoxels(s));
        mSpine = toVoxels(kSpine);
        mVertebraPeriod = kVertebraPeriod * mScale.z;
        mDiscGap = kDiscGap * mScale.z;
        mMandibleFront = toVoxel(kMandibleFront, 1);
        mMandibleTop = toVoxel(kMandibleTop, 2);
        mMandibleDepth = 0.6f * mSkullDepth;
        mMandibleThickness = 1.2f * mSkullThickness;
    }

    void fillRow(int64_t y, int64_t z, Scratch& s, float* out) const {
        const float fy = float(y), fz = float(z);
        whiteNoiseRow(latticeKey(mSeed, y, z), mNx, s.noise.data());
        for (int x = 0; x < mNx; ++x) out[x] = kAir + kAirNoise * s.noise[x];

        // The smooth union lowers distances by at most k / 4, and only where the two are within
        // k of each other, so beyond these margins skipping a part changes no weight.
        const float craniumMargin = kEdgeHalfWidth + 0.25f * mSkinBlend + 1.0f;
        const float partMargin = kEdgeHalfWidth + 1.25f * mSkinBlend + 1.0f;
        const RowShape cranium = rowShape(craniumShape(fy, fz), fy, fz, craniumMargin, mNx);
        const RowShape neck = rowShape(mNeck, fy, fz, partMargin, mNx);
        const RowShape jaw = rowShape(mJaw, fy, fz, partMargin, mNx);
        const RowShape nose = rowShape(mNose, fy, fz, partMargin, mNx);
        const Span head = hull(hull(cranium.span, neck.span), hull(jaw.span, nose.span));
        if (head.begin >= head.end) return;

        for (int x = head.begin; x < head.end; ++x) {
            s.cranium[x] = cranium.distance(float(x));
            s.skin[x] = s.cranium[x];
        }
        for (const RowShape* part : {&neck, &jaw, &nose}) {
            const Span span = intersect(part->span, head);
            for (int x = span.begin; x < span.end; ++x)
                s.skin[x] = smoothUnion(s.skin[x], part->distance(float(x)), mSkinBlend);
        }
        fillSoftTissue(head, s, out);
        fillSkull(head, fy, fz, s);
        addInnerBones(head, fy, fz, jaw, s);
        fillFluid(head, fy, fz, s, out);
        for (int x = head.begin; x < head.end; ++x)
            out[x] = lerp(out[x], kBone + kBoneNoise * s.noise[x], s.bone[x]);
    }

private:
    float toVoxel(float u, int axis) const { return (u + 1.0f) * mScale[axis]; }

    Shape toVoxels(const NormalisedShape& n) const {
        Shape s;
        for (int a = 0; a < 3; ++a) {
            s.center[a] = toVoxel(n.center[a], a);
            s.radii[a] = n.radii[a] * mScale[a];
        }
        s.capAxis = n.capAxis;
        if (n.capAxis != 0) s.capLimit = toVoxel(n.capLimit, n.capAxis);
        s.capSign = n.capSign;
        return s;
    }

    // The egg's radii depend only on which side of the centre the row is, so each row sees a
    // plain ellipsoid; the halves meet with a common tangent.
    Shape craniumShape(float y, float z) const {
        Shape s;
        for (int a = 0; a < 3; ++a) s.center[a] = toVoxel(kCraniumCenter[a], a);
        s.radii.x = kCraniumRx * mScale.x;
        s.radii.y = (y >= s.center.y ? kCraniumRyFront : kCraniumRyBack) * mScale.y;
        s.radii.z = (z >= s.center.z ? kCraniumRzTop : kCraniumRzBottom) * mScale.z;
        return s;
    }

    void fillSoftTissue(Span head, Scratch& s, float* out) const {
        const float brainDepth = mSkullDepth + mSkullThickness;
        for (int x = head.begin; x < head.end; ++x) {
            const float n = s.noise[x];
            float v = lerp(out[x], kTissue + kTissueNoise * n, insideWeight(s.skin[x]));
            out[x] = lerp(v, kBrain + kBrainNoise * n, insideWeight(s.cranium[x] + brainDepth));
        }
    }

    void fillSkull(Span head, float y, float z, Scratch& s) const {
        const float halfThickness = 0.5f * mSkullThickness;
        const float middle = mSkullDepth + halfThickness;
        for (int x = head.begin; x < head.end; ++x)
            s.bone[x] = insideWeight(std::abs(s.cranium[x] + middle) - halfThickness);
        const float margin = kEdgeHalfWidth + 1.0f;
        for (const Shape& hole : mHoles) {
            const RowShape r = rowShape(hole, y, z, margin, mNx);
            const Span span = intersect(r.span, head);
            for (int x = span.begin; x < span.end; ++x)
                s.bone[x] *= 1.0f - insideWeight(r.distance(float(x)));
        }
    }

    void addInnerBones(Span head, float y, float z, const RowShape& jaw, Scratch& s) const {
        const float margin = kEdgeHalfWidth + 1.0f;
        for (const Shape& bone : mInnerBones) {
            const RowShape r = rowShape(bone, y, z, margin, mNx);
            const Span span = intersect(r.span, head);
            for (int x = span.begin; x < span.end; ++x)
                s.bone[x] = std::max(s.bone[x], insideWeight(r.distance(float(x))));
        }
        const RowShape spine = rowShape(mSpine, y, z, margin, mNx);
        const float discs = std::max(spine.cap, discDistance(z));
        if (discs < kEdgeHalfWidth) {
            const Span span = intersect(spine.span, head);
            for (int x = span.begin; x < span.end; ++x)
                s.bone[x] =
                    std::max(s.bone[x], insideWeight(std::max(spine.distance(float(x)), discs)));
        }
        // The mandible is the jaw's shell, kept to the front and bottom by two row constants.
        const float gate = std::max(mMandibleFront - y, z - mMandibleTop);
        if (gate < kEdgeHalfWidth) {
            const float halfThickness = 0.5f * mMandibleThickness;
            const float middle = mMandibleDepth + halfThickness;
            const Span span = intersect(jaw.span, head);
            for (int x = span.begin; x < span.end; ++x) {
                const float shell = std::abs(jaw.distance(float(x)) + middle) - halfThickness;
                s.bone[x] = std::max(s.bone[x], insideWeight(std::max(shell, gate)));
            }
        }
    }

    // Signed distance along z to the gaps between vertebrae (negative inside a vertebra).
    float discDistance(float z) const {
        const float t = (mSpine.capLimit - z) / mVertebraPeriod;
        const float phase = t - std::floor(t);
        return 0.5f * mDiscGap - mVertebraPeriod * std::min(phase, 1.0f - phase);
    }

    void fillFluid(Span head, float y, float z, Scratch& s, float* out) const {
        const float margin = kEdgeHalfWidth + 1.0f;
        for (const Shape& ventricle : mVentricles) {
            const RowShape r = rowShape(ventricle, y, z, margin, mNx);
            const Span span = intersect(r.span, head);
            for (int x = span.begin; x < span.end; ++x)
                out[x] = lerp(out[x], kFluid + kFluidNoise * s.noise[x],
                              insideWeight(r.distance(float(x))));
        }
    }

    int mNx;
    uint64_t mSeed;
    glm::vec3 mScale{1.0f};  // voxels per normalised unit, per axis
    float mUnit = 1.0f;      // voxels per normalised unit along the smallest axis
    float mSkullDepth = 0.0f, mSkullThickness = 0.0f, mSkinBlend = 0.0f;
    Shape mNeck, mJaw, mNose, mSpine;
    std::vector<Shape> mHoles, mInnerBones, mVentricles;
    float mVertebraPeriod = 1.0f, mDiscGap = 0.0f;
    float mMandibleFront = 0.0f, mMandibleTop = 0.0f;
    float mMandibleDepth = 0.0f, mMandibleThickness = 0.0f;
};

// ---- Turbulence: fractal sum of gradient noise.

constexpr int kMaxOctaves = 6;
constexpr double kBaseCells = 6.0;      // lattice cells across the smallest dimension
constexpr double kMinCellVoxels = 2.0;  // finer octaves would only alias into white noise
// |noise sum| rarely exceeds this; values are scaled so that it maps to the type's range.
constexpr float kTurbulenceBound = 0.8f;

inline float fade(float t) {
    return t * t * t * (t * (t * 6.0f - 15.0f) + 10.0f);
}

// A gradient drawn uniformly from the cube [-1, 1]^3: 21 bits per component.
inline glm::vec3 gradient(uint64_t h) {
    constexpr float kScale = 2.0f / float(1 << 21);
    const auto component = [&](int shift) {
        return float((h >> shift) & ((1u << 21) - 1)) * kScale - 1.0f;
    };
    return {component(0), component(21), component(42)};
}

class TurbulenceModel {
    struct Octave;

public:
    // Per-task state: each octave's gradients along the four lattice lines around the current
    // row, kept while consecutive rows stay between the same lines, and the columns' sums.
    struct Scratch {
        struct Lines {
            int64_t iy = std::numeric_limits<int64_t>::min(), iz = 0;
            std::vector<float> gx[4], gy[4], gz[4];
        };
        std::vector<Lines> lines;
        std::vector<float> slopes, offsets;
        explicit Scratch(const TurbulenceModel& m) : lines(m.mOctaves.size()) {
            size_t most = 0;
            for (const Octave& o : m.mOctaves) most = std::max(most, size_t(o.columns));
            slopes.resize(most);
            offsets.resize(most);
        }
    };

    TurbulenceModel(const SynthParams& p, float center, float scale)
        : mNx(int(p.dims[0])), mCenter(center), mScale(scale) {
        const int64_t smallest = std::min({p.dims[0], p.dims[1], p.dims[2]});
        double cellsPerVoxel = kBaseCells / double(smallest);
        float amplitude = 1.0f;
        for (int o = 0; o < kMaxOctaves; ++o) {
            if (o > 0 && 1.0 / cellsPerVoxel < kMinCellVoxels) break;
            mOctaves.push_back(makeOctave(p.seed, o, cellsPerVoxel, amplitude));
            cellsPerVoxel *= 2.0;
            amplitude *= 0.5f;
        }
    }

    void fillRow(int64_t y, int64_t z, Scratch& s, float* out) const {
        std::fill(out, out + mNx, 0.0f);
        for (size_t o = 0; o < mOctaves.size(); ++o) addOctave(mOctaves[o], y, z, s, o, out);
        for (int x = 0; x < mNx; ++x) out[x] = mCenter + mScale * out[x];
    }

private:
    struct Octave {
        double cellsPerVoxel = 1.0;
        double offset[3] = {0.0, 0.0, 0.0};
        uint64_t key = 0;
        float amplitude = 1.0f;
        // Where each x falls in the lattice is the same for every row: the fraction across its
        // cell, that fraction faded, and the run of samples each column's cell covers.
        int64_t firstColumn = 0, columns = 0;
        std::vector<int> runStart;  // columns + 1 entries; the last column starts no cell
        std::vector<float> fraction, faded;
    };

    Octave makeOctave(uint64_t seed, int index, double cellsPerVoxel, float amplitude) const {
        Octave o;
        o.cellsPerVoxel = cellsPerVoxel;
        o.key = mix64(seed + uint64_t(index + 1) * kGolden64);
        // Offsets keep the octaves' lattices (where each octave is zero) from lining up.
        for (int a = 0; a < 3; ++a)
            o.offset[a] = double(mix64(o.key + uint64_t(a)) >> 11) * 0x1.0p-53;
        o.amplitude = amplitude;
        // Positions are never negative, so truncation is floor.
        o.firstColumn = int64_t(o.offset[0]);
        o.columns = int64_t(double(mNx - 1) * cellsPerVoxel + o.offset[0]) + 2 - o.firstColumn;
        o.runStart.assign(size_t(o.columns + 1), mNx);
        for (int x = mNx - 1; x >= 0; --x) {
            const double px = double(x) * cellsPerVoxel + o.offset[0];
            const int64_t ix = int64_t(px);
            o.runStart[size_t(ix - o.firstColumn)] = x;
            o.fraction.push_back(float(px - double(ix)));
        }
        std::reverse(o.fraction.begin(), o.fraction.end());
        // Columns no sample falls in start where the next one does.
        for (int64_t c = o.columns - 1; c >= 0; --c)
            o.runStart[size_t(c)] = std::min(o.runStart[size_t(c)], o.runStart[size_t(c + 1)]);
        for (float f : o.fraction) o.faded.push_back(fade(f));
        return o;
    }

    void loadLines(const Octave& o, int64_t iy, int64_t iz, Scratch::Lines& lines) const {
        if (lines.iy == iy && lines.iz == iz && !lines.gx[0].empty()) return;
        lines.iy = iy;
        lines.iz = iz;
        for (int k = 0; k < 4; ++k) {
            const uint64_t key = latticeKey(o.key, iy + (k & 1), iz + (k >> 1));
            lines.gx[k].resize(size_t(o.columns));
            lines.gy[k].resize(size_t(o.columns));
            lines.gz[k].resize(size_t(o.columns));
            for (int64_t c = 0; c < o.columns; ++c) {
                const glm::vec3 g = gradient(latticeHash(key, o.firstColumn + c));
                lines.gx[k][size_t(c)] = g.x;
                lines.gy[k][size_t(c)] = g.y;
                lines.gz[k][size_t(c)] = g.z;
            }
        }
    }

    // Along a row, y and z are fixed, so each lattice column's four corners collapse (after the
    // y-z interpolation) to one linear function of x: slope * fx + offset. Across a cell the
    // noise is then a lerp of two such lines, with constants for the whole run of samples.
    void addOctave(const Octave& o, int64_t y, int64_t z, Scratch& s, size_t index,
                   float* out) const {
        const double py = double(y) * o.cellsPerVoxel + o.offset[1];
        const double pz = double(z) * o.cellsPerVoxel + o.offset[2];
        const int64_t iy = int64_t(py), iz = int64_t(pz);
        const float fy = float(py - double(iy)), fz = float(pz - double(iz));
        const float wy = fade(fy), wz = fade(fz);
        Scratch::Lines& lines = s.lines[index];
        loadLines(o, iy, iz, lines);

        // The octave's amplitude rides along in the corner weights.
        float toSlope[4], toOffsetY[4], toOffsetZ[4];
        for (int k = 0; k < 4; ++k) {
            const int a = k & 1, b = k >> 1;
            const float w = o.amplitude * (a ? wy : 1.0f - wy) * (b ? wz : 1.0f - wz);
            toSlope[k] = w;
            toOffsetY[k] = w * (fy - float(a));
            toOffsetZ[k] = w * (fz - float(b));
        }
        float* slopes = s.slopes.data();
        float* offsets = s.offsets.data();
        for (int64_t c = 0; c < o.columns; ++c) {
            float slope = 0.0f, offset = 0.0f;
            for (int k = 0; k < 4; ++k) {
                slope += toSlope[k] * lines.gx[k][size_t(c)];
                offset +=
                    toOffsetY[k] * lines.gy[k][size_t(c)] + toOffsetZ[k] * lines.gz[k][size_t(c)];
            }
            slopes[c] = slope;
            offsets[c] = offset;
        }
        const float* fraction = o.fraction.data();
        const float* faded = o.faded.data();
        for (int64_t c = 0; c + 1 < o.columns; ++c) {
            const float s0 = slopes[c], o0 = offsets[c];
            const float s1 = slopes[c + 1], o1 = offsets[c + 1] - s1;
            for (int x = o.runStart[size_t(c)]; x < o.runStart[size_t(c + 1)]; ++x) {
                const float n0 = s0 * fraction[x] + o0;
                const float n1 = s1 * fraction[x] + o1;
                out[x] += n0 + (n1 - n0) * faded[x];
            }
        }
    }

    int mNx;
    float mCenter, mScale;
    std::vector<Octave> mOctaves;
};

// ---- Driving the models.

// Rounds to the nearest representable value, saturating; truncation after shifting to a
// non-negative range is a round-half-up that vectorises.
template <class T>
void storeRow(const float* values, int n, T* out) {
    if constexpr (std::is_same_v<T, float>) {
        std::copy(values, values + n, out);
    } else {
        constexpr float lo = float(std::numeric_limits<T>::min());
        constexpr float hi = float(std::numeric_limits<T>::max());
        for (int x = 0; x < n; ++x)
            out[x] = T(int32_t(std::min(std::max(values[x], lo), hi) - lo + 0.5f) + int32_t(lo));
    }
}

template <class Model, class T>
void generate(const Model& model, const Dims3& dims, int64_t z0, int64_t count, T* dst) {
    const int nx = int(dims[0]);
    const int64_t ny = dims[1];
    tbb::parallel_for(tbb::blocked_range<int64_t>(0, count * ny), [&](const auto& rows) {
        typename Model::Scratch scratch(model);
        std::vector<float> values(static_cast<size_t>(nx));
        for (int64_t r = rows.begin(); r != rows.end(); ++r) {
            model.fillRow(r % ny, z0 + r / ny, scratch, values.data());
            storeRow(values.data(), nx, dst + r * nx);
        }
    });
}

// Half the distance from the centre to the nearer end of the type's range.
float turbulenceHalfRange(ScalarType type) {
    switch (type) {
        case ScalarType::U8:
            return 127.0f;
        case ScalarType::I16:
            return 32767.0f;
        case ScalarType::U16:
            return 32767.0f;
        case ScalarType::F32:
            return 1.0f;
    }
    return 1.0f;
}

}  // namespace

double turbulenceIso(ScalarType type) {
    // Half-integers for the integer types, so no sample ever equals the isovalue.
    switch (type) {
        case ScalarType::U8:
            return 127.5;
        case ScalarType::I16:
            return 0.5;
        case ScalarType::U16:
            return 32767.5;
        case ScalarType::F32:
            return 0.0;
    }
    return 0.0;
}

void synthesizeSlices(const SynthParams& params, int64_t z0, int64_t count, void* dst) {
    const Dims3& d = params.dims;
    if (d[0] < 2 || d[1] < 2 || d[2] < 2 || d[0] > std::numeric_limits<int>::max() / 2)
        throw std::invalid_argument("synth: dimensions must be between 2 and 2^30");
    if (const std::string problem = volumeDimsProblem(d); !problem.empty())
        throw std::invalid_argument("synth: " + problem);
    if (z0 < 0 || count < 0 || z0 + count > d[2])
        throw std::invalid_argument("synth: slices [" + std::to_string(z0) + ", " +
                                    std::to_string(z0 + count) + ") outside the volume's " +
                                    std::to_string(d[2]));
    visitScalarType(params.type, [&](auto zero) {
        using T = decltype(zero);
        T* out = static_cast<T*>(dst);
        if (params.kind == SynthKind::Head) {
            if constexpr (std::is_same_v<T, uint8_t>) {
                throw std::invalid_argument(
                    "synth: the head needs values up to ~1900; use "
                    "i16, u16 or f32, not u8");
            } else {
                generate(HeadModel(params), d, z0, count, out);
            }
        } else {
            const float scale = turbulenceHalfRange(params.type) / kTurbulenceBound;
            generate(TurbulenceModel(params, float(turbulenceIso(params.type)), scale), d, z0,
                     count, out);
        }
    });
}

}  // namespace vdiso
