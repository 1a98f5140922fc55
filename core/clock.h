// The clock every timing in vdiso reads (a steady one: wall time that never jumps), and the
// seconds since a moment of it.
#pragma once

#include <chrono>

namespace vdiso {

using Clock = std::chrono::steady_clock;

inline double secondsSince(Clock::time_point start) {
    return std::chrono::duration<double>(Clock::now() - start).count();
}

}  // namespace vdiso
