// mpi/slab_partition.h, the arithmetic of who reads, owns and encodes what in vdiso-mpi
// convert, against its invariants for every small shape (no MPI needed: header-only). A rank
// that computes a slice must hold what the filter reads; a layer must be encoded once, by a
// rank that holds its slices.
#include <gtest/gtest.h>

#include "core/brick_levels.h"
#include "mpi/slab_partition.h"

namespace vdiso::mpi {
namespace {

bool contains(const IndexRange& r, int64_t s) { return r.begin <= s && s < r.end; }

TEST(SlabPartition, EverySliceAndLayerHasOneOwnerWhoHoldsWhatItNeeds) {
    for (int64_t depth : {2, 3, 9, 17, 18, 33, 34, 65, 100, 129}) {
        for (int B : {2, 3, 8}) {
            VolumeInfo volume;
            volume.dims = {5, 4, depth};
            const BrickLayout level0(volume.dims, B);
            const std::vector<BrickLevel> levels = brickLevels(volume, B, levelsUntilOneBrick(level0));
            for (int ranks : {1, 2, 3, 4, 7, 40}) {
                SCOPED_TRACE("depth " + std::to_string(depth) + ", B " + std::to_string(B) + ", " +
                             std::to_string(ranks) + " ranks");
                // Level 0's layers: contiguous runs, in rank order, differing by at most one.
                int64_t next = 0;
                for (int r = 0; r < ranks; ++r) {
                    const IndexRange run = level0Layers(level0.brickCounts[2], ranks, r);
                    EXPECT_EQ(run.begin, next);
                    EXPECT_LE(run.size(), (level0.brickCounts[2] + ranks - 1) / ranks);
                    EXPECT_GE(run.size(), level0.brickCounts[2] / ranks);
                    next = run.end;
                }
                EXPECT_EQ(next, level0.brickCounts[2]);
                for (int l = 0; l < int(levels.size()); ++l) {
                    const BrickLayout& lay = levels[size_t(l)].layout;
                    const int64_t n = lay.dims[2];
                    int64_t slice = 0, layer = 0;
                    for (int r = 0; r < ranks; ++r) {
                        const IndexRange own = ownedSlices(levels, l, ranks, r), need = neededSlices(levels, l, ranks, r),
                                         layers = encodedLayers(levels, l, ranks, r);
                        EXPECT_EQ(own.begin, slice) << "level " << l << " rank " << r;
                        EXPECT_EQ(layers.begin, layer) << "level " << l << " rank " << r;
                        slice = std::max(slice, own.end);
                        layer = std::max(layer, layers.end);
                        // Layers it encodes: all their slices held.
                        for (int64_t bk = layers.begin; bk < layers.end; ++bk)
                            for (int64_t s = lay.firstSample(bk); s < lay.firstSample(bk) + lay.side(); ++s)
                                EXPECT_TRUE(contains(need, lay.clampSample(2, s)))
                                    << "level " << l << " rank " << r << " layer " << bk << " slice " << s;
                        // Next-level slices it computes: 2k owned, 2k-1 .. 2k+1 held (level 0:
                        // read from the input).
                        if (size_t(l) + 1 == levels.size()) continue;
                        const IndexRange held = l == 0 ? level0ReadSlices(level0, ranks, r) : need;
                        const IndexRange next1 = ownedSlices(levels, l + 1, ranks, r);
                        for (int64_t k = next1.begin; k < next1.end; ++k) {
                            EXPECT_TRUE(contains(own, std::min(2 * k, n - 1))) << "level " << l + 1 << " slice " << k;
                            for (int64_t s = 2 * k - 1; s <= 2 * k + 1; ++s)
                                EXPECT_TRUE(contains(held, std::clamp<int64_t>(s, 0, n - 1)))
                                    << "level " << l + 1 << " slice " << k << " needs " << s;
                        }
                        if (l == 0) {
                            EXPECT_EQ(neededSlices(levels, 0, ranks, r).size(), held.size());
                        }
                    }
                    EXPECT_EQ(slice, n) << "level " << l;
                    EXPECT_EQ(layer, lay.brickCounts[2]) << "level " << l;
                }
            }
        }
    }
}

}  // namespace
}  // namespace vdiso::mpi
