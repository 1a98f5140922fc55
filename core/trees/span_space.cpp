#include "core/trees/span_space.h"

#include <algorithm>
#include <numeric>

#include "core/check.h"
#include "core/kernel/iso.h"

namespace vdiso {

namespace {

struct BuildRange {
    uint32_t lo, hi;
    bool splitOnMin;
};

}  // namespace

SpanSpaceTree::SpanSpaceTree(std::span<const float> mins, std::span<const float> maxs) {
    VDISO_CHECK_EQ(mins.size(), maxs.size());
    const size_t n = mins.size();
    mIds.resize(n);
    std::iota(mIds.begin(), mIds.end(), 0u);
    // Place medians top-down with nth_element: each range's median goes to its middle slot.
    std::vector<BuildRange> stack{{0, uint32_t(n), true}};
    while (!stack.empty()) {
        const BuildRange r = stack.back();
        stack.pop_back();
        if (r.hi - r.lo <= 1) continue;
        const uint32_t mid = r.lo + (r.hi - r.lo) / 2;
        auto key = [&](uint32_t id) { return r.splitOnMin ? mins[id] : maxs[id]; };
        std::nth_element(mIds.begin() + r.lo, mIds.begin() + mid, mIds.begin() + r.hi,
                         [&](uint32_t a, uint32_t b) { return key(a) < key(b); });
        stack.push_back({r.lo, mid, !r.splitOnMin});
        stack.push_back({mid + 1, r.hi, !r.splitOnMin});
    }
    mPoints.resize(n);
    for (size_t i = 0; i < n; ++i) mPoints[i] = {mins[mIds[i]], maxs[mIds[i]]};
}

template <class Visit>
void SpanSpaceTree::visitActive(double iso, Visit&& visit) const {
    std::vector<BuildRange> stack;
    stack.reserve(64);
    if (!mIds.empty()) stack.push_back({0, uint32_t(mIds.size()), true});
    while (!stack.empty()) {
        const BuildRange r = stack.back();
        stack.pop_back();
        if (r.lo >= r.hi) continue;
        const uint32_t mid = r.lo + (r.hi - r.lo) / 2;
        const Point& p = mPoints[mid];
        if (rangeHoldsIso(p.min, p.max, iso)) visit(mid);
        // Left half: keys <= the median's; right half: keys >= it.
        if (r.splitOnMin) {
            stack.push_back({r.lo, mid, false});  // smaller mins may still be <= iso
            if (p.min <= iso) stack.push_back({mid + 1, r.hi, false});
        } else {
            if (iso < p.max) stack.push_back({r.lo, mid, true});
            stack.push_back({mid + 1, r.hi, true});  // larger maxes may still be > iso
        }
    }
}

void SpanSpaceTree::query(double iso, std::vector<uint32_t>& out) const {
    visitActive(iso, [&](uint32_t slot) { out.push_back(mIds[slot]); });
}

size_t SpanSpaceTree::countActive(double iso) const {
    size_t count = 0;
    visitActive(iso, [&](uint32_t) { ++count; });
    return count;
}

}  // namespace vdiso
