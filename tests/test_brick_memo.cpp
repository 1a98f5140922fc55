// What is kept of a brick across view-dependent extractions (core/trees/brick_memo.h): meta-cell
// ranges (core/trees/meta_cell_range_cache.h) and the parts coarse levels lose
// (core/lod/thin_parts.h).
#include <gtest/gtest.h>

#include "cache/brick_cache.h"
#include "core/camera.h"
#include "core/extract/extract_view.h"
#include "core/lod/thin_parts.h"
#include "core/trees/meta_cell_range_cache.h"
#include "core/synth/synth.h"
#include "core/view_presets.h"
#include "io/store/brick_store.h"
#include "io/store/store_writer.h"
#include "tests/extract_test_util.h"
#include "tests/test_util.h"

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

// A brick's value is made again for another key (an isovalue), and kept for the last one.
TEST(BrickMemo, MakesAgainForAnotherKey) {
    BrickMemo<int> memo(4);
    int made = 0;
    auto make = [&] { return ++made; };
    EXPECT_EQ(*memo.get(7, 1.5, make), 1);
    EXPECT_EQ(*memo.get(7, 1.5, make), 1);
    EXPECT_EQ(*memo.get(7, 2.5, make), 2);
    EXPECT_EQ(*memo.get(7, 2.5, make), 2);
    EXPECT_EQ(memo.size(), 1u);
    BrickMemo<int> none(0);  // keeps nothing
    EXPECT_EQ(*none.get(7, 1.5, make), 3);
    EXPECT_EQ(*none.get(7, 1.5, make), 4);
    EXPECT_EQ(none.size(), 0u);
}

// A plate one voxel thick that the coarse levels lose, seen from far enough for them: frames
// that take its lost parts from the memo draw the same points as frames that find them anew.
TEST(BrickMemo, FramesWithKeptLostPartsDrawTheSamePoints) {
    test::ScratchDir dir;
    const Dims3 dims{96, 96, 96};
    test::MemoryVolume volume(dims, ScalarType::U16);
    test::fillBallBesidePlate(volume);
    StoreWriteOptions w;
    w.brickSize = 8;
    writeBrickStore(volume, dir.file("plate.vdiso"), w);
    const BrickStoreReader store(dir.file("plate.vdiso"));
    const VolumeInfo& info = store.volume();
    LostPartMemo kept(1000);
    int64_t points = 0;
    for (const Camera& camera : orbitCameras(ViewPreset::Normal, info.origin, info.worldMax(), 300, 300, 4)) {
        Camera far = camera;
        far.eye = far.target + (far.eye - far.target) * 10.0;
        far.zNear = far.zFar = 0;
        fitClipPlanes(far, info.origin, info.worldMax());
        ViewExtractOptions with = ViewExtractOptions::sage(550);
        with.lodError = 1;
        ViewExtractOptions without = with;
        with.lostParts = &kept;
        TriangleMesh a, b;
        PointSet pa, pb;
        BrickCache cache(store, 64u << 20);
        const ExtractStats s = extractViewDependent(cache, far, with, a, pa);
        extractViewDependent(cache, far, without, b, pb);
        EXPECT_EQ(a.indices, b.indices);
        EXPECT_EQ(pa.positions, pb.positions);
        EXPECT_EQ(pa.normals, pb.normals);
        points += s.view.thinPartPoints;
    }
    EXPECT_GT(points, 0);  // the plate was lost, and drawn as points
    EXPECT_GT(kept.size(), 0u);
}

}  // namespace
}  // namespace vdiso
