#include "core/simd.h"

#include <cstdlib>
#include <cstring>

namespace vdiso {

bool simdLevelRuns(SimdLevel level) {
    switch (level) {
        case SimdLevel::Baseline: return true;
        case SimdLevel::Avx2:
#if VDISO_HAS_AVX2_PATHS
            return __builtin_cpu_supports("avx2");
#else
            return false;
#endif
    }
    return false;
}

SimdLevel simdLevel() {
    static const SimdLevel chosen = [] {
        const char* forced = std::getenv("VDISO_SIMD");
        if (forced && std::strcmp(forced, "baseline") == 0) return SimdLevel::Baseline;
        return simdLevelRuns(SimdLevel::Avx2) ? SimdLevel::Avx2 : SimdLevel::Baseline;
    }();
    return chosen;
}

const char* simdLevelName(SimdLevel level) {
    return level == SimdLevel::Avx2 ? "avx2" : "baseline";
}

}  // namespace vdiso
