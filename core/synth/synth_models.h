// The generators behind synthesizeSlices (core/synth/synth.h), one a source file: each fills slices
// [z0, z0 + count) of params.type samples into dst. Internal to core/synth/synth.cpp.
#pragma once

#include <cstdint>

#include "core/synth/synth.h"

namespace vdiso::synth_detail {

// Throws std::invalid_argument for u8, which cannot hold the head's values.
void synthesizeHead(const SynthParams& params, int64_t z0, int64_t count, void* dst);
void synthesizeTurbulence(const SynthParams& params, int64_t z0, int64_t count, void* dst);

}  // namespace vdiso::synth_detail
