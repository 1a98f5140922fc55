// The SSE2 row classification (core/kernel/row_classify.h) gives the bits IsoThreshold::above
// gives sample by sample: every type, row lengths 1 to 64, thresholds inside, at and beyond the
// type's range, floats with NaN, infinities and isovalues between two floats. The rows lie in a
// longer array, as a brick's do: the last group of 16 is read whole.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>
#include <vector>

#include "core/kernel/row_classify.h"

namespace vdiso {
namespace {

template <class T>
void expectEveryRowAsTheScalarTest(const std::vector<double>& isos, std::mt19937& rng) {
    std::vector<T> samples(80);
    for (int round = 0; round < 200; ++round) {
        for (T& v : samples) {
            if constexpr (std::is_floating_point_v<T>) {
                const int pick = int(rng() % 12);
                v = pick == 0 ? NAN : pick == 1 ? INFINITY : pick == 2 ? -INFINITY
                  : pick == 3 ? std::nextafter(T(0.5), T(1)) : T(int(rng() % 21) - 10) * T(0.25);
            } else {
                v = T(std::numeric_limits<T>::min() + int64_t(rng() % (uint64_t(std::numeric_limits<T>::max()) -
                                                                           int64_t(std::numeric_limits<T>::min()) + 1)));
                if (rng() % 3 == 0) v = T(int(rng() % 7) - 3 + 100);
            }
        }
        for (double iso : isos) {
            const IsoThreshold<T> t(iso);
            for (int n = 1; n <= 64; ++n) {
                uint64_t expected = 0;
                for (int i = 0; i < n; ++i) expected |= uint64_t(t.above(samples[size_t(i)])) << i;
                ASSERT_EQ(aboveBits(samples.data(), n, t), expected) << "iso " << iso << " n " << n;
            }
        }
    }
}

TEST(RowClassify, EveryTypeGivesTheBitsOfTheScalarTest) {
    std::mt19937 rng(7);
    const std::vector<double> integers{-1e300, -70000, -32769, -32768.5, -32768, -1.5, -0.5, 0, 0.5, 99.5, 100, 101.25,
                                       254.5, 255, 255.5, 32766.5, 32767, 65534.5, 65535, 70000, 1e300};
    expectEveryRowAsTheScalarTest<uint8_t>(integers, rng);
    expectEveryRowAsTheScalarTest<int16_t>(integers, rng);
    expectEveryRowAsTheScalarTest<uint16_t>(integers, rng);
    expectEveryRowAsTheScalarTest<float>({-1e300, -3.5e38, -1, -0.25, 0, 0.1, 0.5, 0.5000001, 2.5, 3.4e38, 1e300}, rng);
}

TEST(RowClassify, BitCountCountsTheSetBits) {
    std::mt19937_64 rng(3);
    for (int k = 0; k < 10000; ++k) {
        const uint64_t x = rng() & rng();
        EXPECT_EQ(bitCount(x), __builtin_popcountll(x));
    }
    EXPECT_EQ(bitCount(~uint64_t(0)), 64);
    EXPECT_EQ(bitCount(0), 0);
}

}  // namespace
}  // namespace vdiso
