#include "core/synth/synth.h"

#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <cmath>
#include <cstring>
#include <stdexcept>
#include <vector>

#include "io/readers/volume_open.h"
#include "tests/reader_test_util.h"

namespace vdiso {
namespace {

std::vector<unsigned char> synthesize(const SynthParams& p, int64_t slab) {
    const size_t sliceBytes = size_t(p.dims[0] * p.dims[1]) * scalarSize(p.type);
    std::vector<unsigned char> bytes(sliceBytes * size_t(p.dims[2]));
    for (int64_t z = 0; z < p.dims[2]; z += slab) {
        const int64_t count = std::min(slab, p.dims[2] - z);
        synthesizeSlices(p, z, count, bytes.data() + size_t(z) * sliceBytes);
    }
    return bytes;
}

// Samples as doubles, whatever the type.
std::vector<double> synthesizeValues(const SynthParams& p) {
    const std::vector<unsigned char> bytes = synthesize(p, p.dims[2]);
    return visitScalarType(p.type, [&](auto zero) {
        using T = decltype(zero);
        std::vector<double> values(bytes.size() / sizeof(T));
        for (size_t i = 0; i < values.size(); ++i) {
            T v;
            std::memcpy(&v, bytes.data() + i * sizeof(T), sizeof(T));
            values[i] = double(v);
        }
        return values;
    });
}

SynthParams params(SynthKind kind, Dims3 dims, ScalarType type, uint64_t seed = 1) {
    SynthParams p;
    p.kind = kind;
    p.dims = dims;
    p.type = type;
    p.seed = seed;
    return p;
}

// Index of normalised coordinate u (the volume spans [-1, 1] on each axis).
int64_t indexOf(double u, int64_t n) {
    return std::lround((u + 1.0) * 0.5 * double(n - 1));
}

struct Crossing {
    double iso;
    bool upwards;
    bool operator==(const Crossing&) const = default;
};

// The isovalue crossings met walking from `start` in steps of `step` (both in samples) to the
// volume's edge, in order.
std::vector<Crossing> crossingsAlong(const std::vector<double>& v, Dims3 dims, Dims3 start,
                                     Dims3 step, std::vector<double> isos) {
    std::vector<Crossing> found;
    auto at = [&](const Dims3& p) { return v[size_t((p[2] * dims[1] + p[1]) * dims[0] + p[0])]; };
    auto inside = [&](const Dims3& p) {
        for (int a = 0; a < 3; ++a)
            if (p[a] < 0 || p[a] >= dims[a]) return false;
        return true;
    };
    Dims3 p = start;
    double previous = at(p);
    for (;;) {
        for (int a = 0; a < 3; ++a) p[a] += step[a];
        if (!inside(p)) break;
        const double current = at(p);
        for (double iso : isos) {
            if (previous < iso && current >= iso) found.push_back({iso, true});
            if (previous >= iso && current < iso) found.push_back({iso, false});
        }
        previous = current;
    }
    return found;
}

TEST(SynthDeterminism, SlabSplitGivesSameBytes) {
    const Dims3 dims{48, 48, 48};
    for (SynthKind kind : {SynthKind::Head, SynthKind::Turbulence}) {
        for (ScalarType type :
             {ScalarType::U8, ScalarType::I16, ScalarType::U16, ScalarType::F32}) {
            if (kind == SynthKind::Head && type == ScalarType::U8) continue;
            const SynthParams p = params(kind, dims, type, 7);
            EXPECT_EQ(synthesize(p, 48), synthesize(p, 5)) << scalarTypeName(type);
        }
    }
}

TEST(SynthDeterminism, ThreadCountGivesSameBytes) {
    for (SynthKind kind : {SynthKind::Head, SynthKind::Turbulence}) {
        const SynthParams p = params(kind, {40, 44, 48}, ScalarType::U16, 5);
        const std::vector<unsigned char> parallel = synthesize(p, 48);
        tbb::global_control serial(tbb::global_control::max_allowed_parallelism, 1);
        EXPECT_EQ(parallel, synthesize(p, 48));
    }
}

TEST(SynthDeterminism, AnisotropicSlabSplitGivesSameBytes) {
    for (SynthKind kind : {SynthKind::Head, SynthKind::Turbulence}) {
        const SynthParams p = params(kind, {37, 52, 29}, ScalarType::F32, 3);
        EXPECT_EQ(synthesize(p, 29), synthesize(p, 4));
    }
}

TEST(SynthDeterminism, SeedChangesData) {
    for (SynthKind kind : {SynthKind::Head, SynthKind::Turbulence}) {
        const Dims3 dims{32, 32, 32};
        const auto a = synthesize(params(kind, dims, ScalarType::U16, 1), 32);
        const auto b = synthesize(params(kind, dims, ScalarType::U16, 2), 32);
        EXPECT_EQ(a, synthesize(params(kind, dims, ScalarType::U16, 1), 32));
        EXPECT_NE(a, b);
    }
}

TEST(Synth, RejectsSlicesOutsideTheVolume) {
    const SynthParams p = params(SynthKind::Turbulence, {8, 8, 8}, ScalarType::U8);
    std::vector<uint8_t> buffer(8 * 8 * 8);
    EXPECT_THROW(synthesizeSlices(p, 4, 5, buffer.data()), std::invalid_argument);
    EXPECT_THROW(synthesizeSlices(p, -1, 1, buffer.data()), std::invalid_argument);
}

TEST(SynthHead, U8Throws) {
    const SynthParams p = params(SynthKind::Head, {8, 8, 8}, ScalarType::U8);
    std::vector<uint8_t> buffer(8 * 8 * 8);
    EXPECT_THROW(synthesizeSlices(p, 0, 8, buffer.data()), std::invalid_argument);
}

TEST(SynthHead, CornerIsAirAndCentreIsSoftTissue) {
    for (ScalarType type : {ScalarType::I16, ScalarType::U16, ScalarType::F32}) {
        const Dims3 dims{64, 64, 64};
        const std::vector<double> v = synthesizeValues(params(SynthKind::Head, dims, type));
        EXPECT_LT(v.front(), kHeadSkinIso);
        EXPECT_LT(v.back(), kHeadSkinIso);
        const double centre = v[size_t((32 * 64 + 32) * 64 + 32)];
        EXPECT_GT(centre, kHeadSkinIso);
        EXPECT_LT(centre, kHeadBoneIso);
        for (double value : v) {
            ASSERT_GE(value, 0.0);
            ASSERT_LT(value, 2100.0);
        }
    }
}

// From the centre outwards: brain, into the skull and out of it, then out of the skin.
TEST(SynthHead, RayFromCentreCrossesSkullThenSkin) {
    const std::vector<Crossing> expected{
        {kHeadBoneIso, true}, {kHeadBoneIso, false}, {kHeadSkinIso, false}};
    for (Dims3 dims : {Dims3{64, 64, 64}, Dims3{96, 80, 72}, Dims3{160, 160, 160}}) {
        const std::vector<double> v =
            synthesizeValues(params(SynthKind::Head, dims, ScalarType::I16));
        const Dims3 centre{dims[0] / 2, dims[1] / 2, dims[2] / 2};
        for (Dims3 step : {Dims3{1, 0, 0}, Dims3{-1, 0, 0}}) {
            EXPECT_EQ(crossingsAlong(v, dims, centre, step, {kHeadSkinIso, kHeadBoneIso}), expected)
                << dims[0] << "x" << dims[1] << "x" << dims[2] << " step " << step[0];
        }
    }
}

// The face is +y; the eye sockets sit at x = +-0.27, z = -0.02 (normalised). Straight ahead
// through a socket there is no bone; between the sockets there is.
TEST(SynthHead, EyeSocketsAreHolesInTheSkull) {
    const Dims3 dims{96, 96, 96};
    const std::vector<double> v = synthesizeValues(params(SynthKind::Head, dims, ScalarType::U16));
    const int64_t y = indexOf(0.0, dims[1]), z = indexOf(-0.02, dims[2]);
    const Dims3 forward{0, 1, 0};
    for (double x : {-0.27, 0.27}) {
        const auto crossings =
            crossingsAlong(v, dims, {indexOf(x, dims[0]), y, z}, forward, {kHeadBoneIso});
        EXPECT_TRUE(crossings.empty()) << "socket at x = " << x;
        const auto skin =
            crossingsAlong(v, dims, {indexOf(x, dims[0]), y, z}, forward, {kHeadSkinIso});
        EXPECT_EQ(skin, (std::vector<Crossing>{{kHeadSkinIso, false}}));
    }
    const auto between =
        crossingsAlong(v, dims, {indexOf(0.0, dims[0]), y, z}, forward, {kHeadBoneIso});
    EXPECT_EQ(between.size(), 2u);
}

TEST(SynthTurbulence, MedianIsNearIso) {
    for (ScalarType type : {ScalarType::U8, ScalarType::I16, ScalarType::U16, ScalarType::F32}) {
        for (uint64_t seed : {1, 2, 3}) {
            const std::vector<double> v =
                synthesizeValues(params(SynthKind::Turbulence, {64, 64, 64}, type, seed));
            const double iso = turbulenceIso(type);
            size_t above = 0;
            for (double value : v) above += value > iso;
            const double fraction = double(above) / double(v.size());
            EXPECT_GT(fraction, 0.4) << scalarTypeName(type) << " seed " << seed;
            EXPECT_LT(fraction, 0.6) << scalarTypeName(type) << " seed " << seed;
        }
    }
}

// Many sheets of the isosurface along every axis, not one blob.
TEST(SynthTurbulence, RaysCrossManySheets) {
    const Dims3 dims{64, 64, 64};
    const std::vector<double> v =
        synthesizeValues(params(SynthKind::Turbulence, dims, ScalarType::U16));
    const double iso = turbulenceIso(ScalarType::U16);
    for (Dims3 step : {Dims3{1, 0, 0}, Dims3{0, 1, 0}, Dims3{0, 0, 1}}) {
        size_t crossings = 0, rays = 0;
        for (int64_t a = 0; a < 64; a += 8) {
            for (int64_t b = 0; b < 64; b += 8) {
                Dims3 start{a, b, 0};
                if (step[0]) start = {0, a, b};
                if (step[1]) start = {a, 0, b};
                crossings += crossingsAlong(v, dims, start, step, {iso}).size();
                ++rays;
            }
        }
        EXPECT_GT(double(crossings) / double(rays), 2.0);
    }
}

TEST(SynthDeterminism, SkipMatchesReading) {
    for (SynthKind kind : {SynthKind::Head, SynthKind::Turbulence}) {
        const SynthParams p = params(kind, {9, 8, 7}, ScalarType::U16);
        test::expectSkipMatchesRead([&] { return openSynthVolume(p); });
    }
}

}  // namespace
}  // namespace vdiso
