// Meta-cell ranges kept across view-dependent extractions (core/trees/meta_cell_range_cache.h).
#include <gtest/gtest.h>

#include "core/camera.h"
#include "core/extract/extract_view.h"
#include "core/trees/meta_cell_range_cache.h"
#include "core/synth/synth.h"
#include "core/view_presets.h"
#include "tests/extract_test_util.h"

namespace vdiso {
namespace {

TEST(MetaCellRangeCache, ComputesOnceKeepsTheRecentAndMatchesTheExtractor) {
    const auto source = test::synthBrickSource({SynthKind::Head, {48, 48, 48}}, 8);
    BrickExtractor four(source->volume(), source->layout(), 4), two(source->volume(), source->layout(), 2);
    MetaCellRangeCache cache(2);
    const BrickHandle b0 = source->acquire(0), b1 = source->acquire(1), b2 = source->acquire(2);
    const MetaCellRangeCache::Ranges first = cache.get(0, 0, four, b0.samples());
    std::vector<BrickRange> direct;
    four.metaCellRanges(0, b0.samples(), direct);
    ASSERT_EQ(first->size(), direct.size());
    for (size_t m = 0; m < direct.size(); ++m) {
        EXPECT_EQ((*first)[m].minValue, direct[m].minValue);
        EXPECT_EQ((*first)[m].maxValue, direct[m].maxValue);
    }
    EXPECT_EQ(cache.get(0, 0, four, b0.samples()), first);  // kept, not recomputed
    // Another meta-cell size is not served from what was kept for this one.
    EXPECT_NE(cache.get(0, 0, two, b0.samples())->size(), first->size());
    cache.get(0, 0, four, b0.samples());
    cache.get(1, 1, four, b1.samples());
    cache.get(2, 2, four, b2.samples());  // two bricks at most: 0, the least recent, goes
    EXPECT_EQ(cache.size(), 2u);
    EXPECT_NE(cache.get(0, 0, four, b0.samples()), first);
}

// Frames that reuse kept ranges extract what frames without them do.
TEST(MetaCellRangeCache, ExtractionWithKeptRangesIsTheSame) {
    const auto source = test::synthBrickSource({SynthKind::Head, {96, 96, 96}}, 16);
    const VolumeInfo& v = source->volume();
    MetaCellRangeCache kept(1000);
    for (const Camera& camera : orbitCameras(ViewPreset::Normal, v.origin, v.worldMax(), 160, 160, 3)) {
        Camera c = camera;
        fitClipPlanes(c, v.origin, v.worldMax());
        ViewExtractOptions with = ViewExtractOptions::sage(kHeadSkinIso);
        with.rangeCache = &kept;
        TriangleMesh a, b;
        PointSet pa, pb;
        extractViewDependent(*source, c, with, a, pa);
        extractViewDependent(*source, c, ViewExtractOptions::sage(kHeadSkinIso), b, pb);
        EXPECT_EQ(a.positions, b.positions);
        EXPECT_EQ(a.indices, b.indices);
        EXPECT_EQ(pa.positions, pb.positions);
    }
    EXPECT_GT(kept.size(), 0u);
}

}  // namespace
}  // namespace vdiso
