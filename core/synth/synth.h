// Deterministic generated volumes for tests and benchmarks (`vdiso synth`).
//
// head: CT-like, filling about 80% of the volume whatever its dims (shapes scale with each
//   axis). +z is up, +y is the face, x runs ear to ear. Air 0..60; soft tissue ~1000 (+-40)
//   whose outer surface isovalue 600.5 cuts, with a neck leaving through the bottom face and a
//   jaw and nose at the front; a skull shell ~1850 (+-60) a little inside the skin, whose inner
//   and outer faces 1224.5 both cut, with holes (eye sockets and nasal aperture at +y, foramen
//   magnum and two small foramina underneath) so bone shows inner structure; brain ~1050
//   inside it, with fluid-filled ventricles (~350) and dense inner bones (inner ears, sella);
//   spine and mandible at bone values. Materials blend over ~2 voxels, so isosurfaces are
//   smooth rather than staircased. Needs i16, u16 or f32.
// turbulence: a sum of octaves of gradient noise (6 cells across the smallest axis, doubling
//   while cells stay at least 2 voxels, at most 6 octaves), centred on turbulenceIso(type)
//   (about half the samples lie above it), with many sheets of that isosurface along any ray.
//
// Samples are a pure function of (kind, dims, type, seed, position): any slab split and any
// thread count give the same bytes.
#pragma once

#include <cstdint>

#include "core/volume.h"

namespace vdiso {

enum class SynthKind { Head, Turbulence };

struct SynthParams {
    SynthKind kind = SynthKind::Head;
    Dims3 dims{64, 64, 64};
    ScalarType type = ScalarType::U16;
    uint64_t seed = 1;
};

// Isovalues the head's surfaces are designed for.
constexpr double kHeadSkinIso = 600.5;
constexpr double kHeadBoneIso = 1224.5;

// The value around which turbulence is centred, for a given type (its median, approximately).
double turbulenceIso(ScalarType type);

// Fills z-slices [z0, z0 + count) into dst (count * dims[0] * dims[1] samples of params.type).
// Uses all cores through TBB. Throws std::invalid_argument if the head's values do not fit the
// type (a u8 head cannot hold 1224.5).
void synthesizeSlices(const SynthParams& params, int64_t z0, int64_t count, void* dst);

}  // namespace vdiso
