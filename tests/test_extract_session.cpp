// The front ends' extraction session (app/extract_session.h): frames of a path.
#include <gtest/gtest.h>

#include <utility>

#include "app/extract_session.h"
#include "core/camera.h"
#include "core/synth/synth.h"
#include "core/view_presets.h"
#include "io/readers/volume_open.h"
#include "io/store/brick_store.h"
#include "io/store/store_writer.h"
#include "tests/test_util.h"

namespace vdiso {
namespace {

// A frame filling the arrays the frame before handed back (ExtractSession::recycle) holds what
// a session's first frame from the same camera holds, exactly: nothing of the frame before is
// left, on one strip (the mesh appended to) and on two (merged into it).
TEST(ExtractSession, AFrameFillsTheArraysTheLastOneHandedBack) {
    test::ScratchDir dir;
    SynthParams p;
    p.kind = SynthKind::Head;
    p.dims = {64, 64, 64};
    StoreWriteOptions o;
    o.brickSize = 8;
    writeBrickStore(*openSynthVolume(p), dir.file("h.vdiso"), o);
    const BrickStoreReader store(dir.file("h.vdiso"));
    const VolumeInfo& v = store.volume();
    const Camera normal = presetCamera(ViewPreset::Normal, v.origin, v.worldMax(), 200, 200);
    const Camera closeup = presetCamera(ViewPreset::Closeup, v.origin, v.worldMax(), 200, 200);
    for (const int threads : {1, 2}) {
        ExtractSettings s;
        s.method = "sage";
        s.iso = kHeadSkinIso;
        s.threads = threads;
        ExtractSession fresh(store, s);
        const ExtractFrame expected = fresh.extract(closeup);
        ASSERT_GT(expected.mesh.triangleCount(), 0u);

        ExtractSession session(store, s);
        ExtractFrame first = session.extract(normal);
        ASSERT_GT(first.mesh.triangleCount(), expected.mesh.triangleCount());
        session.recycle(std::move(first));
        const ExtractFrame second = session.extract(closeup);
        EXPECT_EQ(second.mesh.firstVertex, 0u);
        EXPECT_TRUE(second.mesh.indices == expected.mesh.indices) << threads << " threads";
        EXPECT_TRUE(second.mesh.positions == expected.mesh.positions) << threads << " threads";
        EXPECT_TRUE(second.mesh.normals == expected.mesh.normals) << threads << " threads";
        EXPECT_TRUE(second.points.positions == expected.points.positions) << threads << " threads";
        EXPECT_EQ(second.stats.triangles, expected.stats.triangles);
    }
}

}  // namespace
}  // namespace vdiso
