// The span-space tree returns exactly the items whose range holds the isovalue.
#include <gtest/gtest.h>

#include <algorithm>
#include <random>

#include "core/kernel/iso.h"
#include "core/trees/span_space.h"

namespace vdiso {
namespace {

TEST(SpanSpace, MatchesBruteForceOnRandomRanges) {
    std::mt19937 rng(7);
    for (int trial = 0; trial < 20; ++trial) {
        const size_t n = size_t(rng() % 3000);
        std::vector<float> mins(n), maxs(n);
        std::uniform_int_distribution<int> value(0, 200);  // integers: many ties
        for (size_t i = 0; i < n; ++i) {
            const int a = value(rng), b = value(rng);
            mins[i] = float(std::min(a, b));
            maxs[i] = float(std::max(a, b));
        }
        const SpanSpaceTree tree(mins, maxs);
        for (double iso : {-1.0, 0.0, 0.5, 17.0, 99.5, 100.0, 199.0, 200.0, 250.0}) {
            std::vector<uint32_t> got;
            tree.query(iso, got);
            std::sort(got.begin(), got.end());
            std::vector<uint32_t> expected;
            for (uint32_t i = 0; i < n; ++i)
                if (rangeHoldsIso(mins[i], maxs[i], iso)) expected.push_back(i);
            ASSERT_EQ(got, expected) << "trial " << trial << " iso " << iso;
            EXPECT_EQ(tree.countActive(iso), expected.size());
        }
    }
}

TEST(SpanSpace, EmptyTree) {
    const SpanSpaceTree tree({}, {});
    EXPECT_EQ(tree.countActive(1.0), 0u);
}

}  // namespace
}  // namespace vdiso
