// View-dependent extraction against the full surface: rendered from the same camera, the SAGE
// and WISE surfaces must reproduce at least 99.5% of the pixels the full surface covers
// (docs/design.md, "Correctness contract"), while extracting fewer triangles and reading no more
// bricks.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdlib>

#include "cache/brick_cache.h"
#include "core/camera.h"
#include "core/extract/extract_full.h"
#include "core/extract/extract_view.h"
#include "core/extract/visible_oracle.h"
#include "core/view_presets.h"
#include "io/store/brick_store.h"
#include "io/render/image_compare.h"
#include "io/render/renderer.h"
#include "io/store/store_writer.h"
#include "io/readers/volume_open.h"
#include "tests/extract_test_util.h"
#include "tests/test_util.h"

namespace vdiso {
namespace {

struct FidelityResult {
    ImageAgreement image;
    uint64_t fullTriangles, viewTriangles, viewPoints;
    int64_t fullBricks, viewBricks;
    VisibleSurfaceOracle oracle;
    bool everyVertexUsed;
};

// The full surface and what it shows from a preset's camera: the same for every extraction
// compared with it, so made once.
struct Reference {
    Camera camera;
    RenderResult picture;
    VisibleSurfaceOracle oracle;
};

Reference referenceView(BrickSource& source, double iso, const TriangleMesh& full, ViewPreset preset) {
    const VolumeInfo& v = source.volume();
    const Camera camera = presetCamera(preset, v.origin, v.worldMax(), 800, 800);  // vdiso extract's default
    RenderResult picture = renderSurface(full, PointSet{}, camera);
    VisibleSurfaceOracle oracle = visibleSurfaceOracle(source, camera, picture.depth, iso);
    return {camera, std::move(picture), oracle};
}

FidelityResult compareWithFull(BrickSource& source, const TriangleMesh& full, int64_t fullBricks,
                               const Reference& reference, const ViewExtractOptions& options) {
    TriangleMesh view;
    PointSet points;
    const ExtractStats s = extractViewDependent(source, reference.camera, options, view, points);
    const RenderResult b = renderSurface(view, points, reference.camera);
    std::vector<uint8_t> used(view.vertexCount(), 0);
    for (uint32_t vertex : view.indices) used[vertex] = 1;
    return {compareImages(reference.picture.image, b.image),
            full.triangleCount(),
            view.triangleCount(),
            points.size(),
            fullBricks,
            s.bricksActive,
            reference.oracle,
            std::find(used.begin(), used.end(), 0) == used.end()};
}

void expectFaithful(BrickSource& source, double iso, const char* what,
                    bool distantHasPoints = false) {
    TriangleMesh full;
    const int64_t fullBricks = extractOctree(source, {iso, 4}, full).bricksActive;
    for (ViewPreset preset : {ViewPreset::Distant, ViewPreset::Normal, ViewPreset::Closeup}) {
        const Reference reference = referenceView(source, iso, full, preset);
        for (int run = 0; run < 3; ++run) {
            // SAGE, SAGE in 3 image strips on 3 threads, WISE.
            const bool sage = run < 2;
            ViewExtractOptions o = sage ? ViewExtractOptions::sage(iso) : ViewExtractOptions::wise(iso);
            o.threads = run == 1 ? 3 : 1;
            const FidelityResult r = compareWithFull(source, full, fullBricks, reference, o);
            const std::string label = std::string(what) + " " + viewPresetName(preset) +
                                      (run == 0 ? " sage" : run == 1 ? " sage 3 strips" : " wise");
            EXPECT_GE(r.image.agreement(), 0.995)
                << label << ": " << r.image.missing << " missing, " << r.image.differentColour
                << " of another colour, of " << r.image.referenceCovered;
            EXPECT_LE(r.viewTriangles, r.fullTriangles) << label;
            EXPECT_LE(r.viewBricks, r.fullBricks) << label;
            if (preset == ViewPreset::Normal) {  // the back of a closed surface is hidden
                EXPECT_LT(double(r.viewTriangles), 0.8 * double(r.fullTriangles)) << label;
            }
            EXPECT_TRUE(r.everyVertexUsed) << label;
            if (!sage) continue;
            // The SAGE issue's targets against the visible-surface oracle: at most 2x its
            // triangles on a normal view, and on a distant view where meta-cells are sub-pixel
            // (points), at most 2 primitives per covered pixel. (These small volumes' distant
            // views have cells under a pixel but meta-cells over one: no points there.)
            if (preset == ViewPreset::Normal) {
                EXPECT_LE(r.viewTriangles, 2 * r.oracle.triangles) << label;
            }
            if (preset == ViewPreset::Distant && distantHasPoints) {
                EXPECT_LE(r.viewTriangles + r.viewPoints, 2 * r.oracle.pixels) << label;
            }
        }
    }
}

TEST(ViewFidelity, GeneratedHeadSkinAndBone) {
    SynthParams p;
    p.kind = SynthKind::Head;
    p.dims = {96, 96, 96};
    auto head = test::synthBrickSource(p, 16);
    expectFaithful(*head, kHeadSkinIso, "head skin");
    expectFaithful(*head, kHeadBoneIso, "head bone");
}

TEST(ViewFidelity, Turbulence) {
    SynthParams p;
    p.kind = SynthKind::Turbulence;
    p.dims = {72, 72, 72};
    auto turbulence = test::synthBrickSource(p, 16);
    expectFaithful(*turbulence, turbulenceIso(ScalarType::U16), "turbulence");
}

TEST(ViewFidelity, RealMri) {
    const std::string path = test::dataFile("ch2.nii.gz");
    if (path.empty())
        GTEST_SKIP() << "VDISO_DATA_DIR has no ch2.nii.gz (scripts/test.sh fetches it)";
    test::ScratchDir scratch;
    auto mri = openVolume(path, {});
    writeBrickStore(*mri, scratch.file("mri.vdiso"), {});
    const BrickStoreReader store(scratch.file("mri.vdiso"));
    BrickCache cache(store, 256u << 20);
    expectFaithful(cache, 40.5, "mri skin", true);
}


TEST(VisibleOracle, BoundsWhatAViewDependentExtractionNeeds) {
    SynthParams p;
    p.kind = SynthKind::Head;
    p.dims = {96, 96, 96};
    auto head = test::synthBrickSource(p, 16);
    const VolumeInfo& v = head->volume();
    const Camera camera = presetCamera(ViewPreset::Normal, v.origin, v.worldMax(), 400, 400);
    TriangleMesh full, view;
    PointSet points;
    extractOctree(*head, {kHeadSkinIso, 4}, full);
    const ExtractStats s = extractViewDependent(*head, camera, ViewExtractOptions::sage(kHeadSkinIso), view, points);
    const RenderResult r = renderSurface(full, PointSet{}, camera);
    const VisibleSurfaceOracle oracle = visibleSurfaceOracle(*head, camera, r.depth, kHeadSkinIso);
    uint64_t covered = 0;
    for (float d : r.depth) covered += d < 1.0f;
    EXPECT_EQ(oracle.pixels, covered);
    EXPECT_GT(oracle.triangles, 0u);
    EXPECT_LE(oracle.cells, oracle.pixels);
    EXPECT_LT(oracle.triangles, full.triangleCount() / 2);  // a closed surface hides its back
    // What the extraction read and produced covers the picture, so it is not below the least.
    EXPECT_GE(uint64_t(s.bricksActive), oracle.bricks);
    EXPECT_GE(view.triangleCount() + points.size(), oracle.cells / 2);
}

}  // namespace
}  // namespace vdiso
