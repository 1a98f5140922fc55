// The generated CT-like head (core/synth/synth.h): shapes in normalised coordinates, filled a row
// at a time.
#include "core/synth/synth_models.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <type_traits>
#include <vector>

#include <glm/vec3.hpp>

#include "core/synth/synth_noise.h"
#include "core/synth/synth_rows.h"
#include "core/synth/synth_shapes.h"

namespace vdiso::synth_detail {
namespace {

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

}  // namespace

void synthesizeHead(const SynthParams& params, int64_t z0, int64_t count, void* dst) {
    visitScalarType(params.type, [&](auto zero) {
        using T = decltype(zero);
        if constexpr (std::is_same_v<T, uint8_t>) {
            throw std::invalid_argument(
                "synth: the head needs values up to ~1900; use "
                "i16, u16 or f32, not u8");
        } else {
            generate(HeadModel(params), params.dims, z0, count, static_cast<T*>(dst));
        }
    });
}

}  // namespace vdiso::synth_detail
