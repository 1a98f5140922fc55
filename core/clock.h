// The clock every timing in vdiso reads (a steady one: wall time that never jumps), the
// seconds since a moment of it, and a timer for calls too frequent and too short to time each.
#pragma once

#include <algorithm>
#include <bit>
#include <chrono>
#include <cstdint>

#include "core/check.h"

namespace vdiso {

using Clock = std::chrono::steady_clock;

inline double secondsSince(Clock::time_point start) {
    return std::chrono::duration<double>(Clock::now() - start).count();
}

// What reading the clock twice costs (the least of 200 tries, measured on the first call).
inline double clockPairSeconds() {
    static const double seconds = [] {
        double least = 1.0;
        for (int i = 0; i < 200; ++i) least = std::min(least, secondsSince(Clock::now()));
        return least;
    }();
    return seconds;
}

// Times one call in `every` (a power of two, checked; kEvery unless said) of a frequent one (a
// per-cell test, a polygon's coverage) and counts it `every` times, less the clock's own cost: a
// clock read costs about what such a call does, so reading it around every call would double
// what it measures. A sample over kInterrupted is dropped: the thread was taken off its core
// (counted 32 times, one such sample made a frame's coverage seven times its whole extraction).
// One in 128: at one in 32 the clock reads were 1.7 % of a SAGE frame; a normal view still
// takes thousands of samples a timer. Calls long enough to time each (a meta-cell) take
// every = 1.
class SampledTimer {
public:
    static constexpr uint32_t kEvery = 128;
    static constexpr double kInterrupted = 200e-6;

    explicit SampledTimer(uint32_t every = kEvery) : mEvery(every) { VDISO_CHECK(std::has_single_bit(every)); }

    // One place that makes the call, so that it inlines as it would untimed.
    template <class F>
    auto operator()(double& seconds, F&& call) {
        const bool sampled = (++mTick & (mEvery - 1)) == 0;
        Clock::time_point start;
        if (sampled) [[unlikely]]
            start = Clock::now();
        auto result = call();
        if (sampled) [[unlikely]] {
            const double sample = secondsSince(start) - clockPairSeconds();
            // (Timing every call, an interruption counts once: nothing is dropped.)
            if (mEvery == 1 || sample < kInterrupted) seconds += mEvery * std::max(sample, 0.0);
        }
        return result;
    }

private:
    uint32_t mEvery;
    uint32_t mTick = 0;
};

}  // namespace vdiso
