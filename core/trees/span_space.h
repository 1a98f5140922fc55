// Span space (Livnat, Shen & Johnson 1996): which items can hold isovalue v?
//
// Each item (a brick, a meta-cell) is the point (min, max) of its sample range; it holds surface
// at v exactly when min <= v < max (core/kernel/iso.h), a quadrant of the span-space plane. A kd-tree
// over the points, split alternately on min and on max, answers the query in
// O(sqrt(n) + k) for n items and k answers, instead of scanning all n.
//
// The tree is a permutation of the items, stored flat: the node of a range [lo, hi) is its
// median element, its children the two halves. Immutable after construction; queries are
// thread-safe.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

namespace vdiso {

class SpanSpaceTree {
public:
    SpanSpaceTree() = default;
    // Builds the tree over items 0..n-1 with ranges [mins[i], maxs[i]]. O(n log n).
    SpanSpaceTree(std::span<const float> mins, std::span<const float> maxs);

    // Appends to `out` the ids of every item with min <= iso < max, in no particular order.
    void query(double iso, std::vector<uint32_t>& out) const;

    // How many items query() would return.
    size_t countActive(double iso) const;

    size_t size() const { return mIds.size(); }

private:
    template <class Visit>
    void visitActive(double iso, Visit&& visit) const;

    struct Point {
        float min, max;
    };
    std::vector<Point> mPoints;  // in tree order
    std::vector<uint32_t> mIds;  // item id of each tree slot
};

}  // namespace vdiso
