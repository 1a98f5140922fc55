// Which instruction set the hot loops use, chosen once at run time from what the CPU offers
// (meshoptimizer's and Masked Occlusion Culling's way): the x86-64 baseline (SSE2) is always
// built, and AVX2 paths are compiled beside it for functions marked VDISO_TARGET_AVX2, so one
// binary runs everywhere and uses AVX2 where the CPU has it. Every path gives the same bits
// (tests/test_scan_convert.cpp and tests/test_screen_box.cpp run each on the same input).
//
// VDISO_SIMD=baseline in the environment at start-up keeps to the baseline (for comparing the
// paths in one binary, or ruling one out).
#pragma once

namespace vdiso {

enum class SimdLevel { Baseline, Avx2 };

// The best level this CPU runs (unless VDISO_SIMD=baseline); computed on the first call.
SimdLevel simdLevel();
// Whether this CPU runs `level`'s code.
bool simdLevelRuns(SimdLevel level);
const char* simdLevelName(SimdLevel level);

}  // namespace vdiso

#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__))
#define VDISO_TARGET_AVX2 __attribute__((target("avx2")))
#define VDISO_HAS_AVX2_PATHS 1
#else
#define VDISO_TARGET_AVX2
#define VDISO_HAS_AVX2_PATHS 0
#endif
