// One view-dependent extraction shared out in parts, as the ranks of an MPI job share it
// (mpi/): parts of the image (columns), or depth-sorted slabs of the volume that take in the
// coverage of the slabs in front of them. Here the parts run one after another in one process;
// together they must draw the single extraction's picture (agreement at least 99.5%), each
// reading only its share.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdlib>
#include <stdexcept>

#include "core/depth_slabs.h"
#include "core/extract_view.h"
#include "core/image_strips.h"
#include "io/image_compare.h"
#include "io/renderer.h"
#include "tests/extract_test_util.h"

namespace vdiso {
namespace {

struct Part {
    TriangleMesh mesh;
    PointSet points;
    ExtractStats stats;
};

// Appends b to a.
void append(Part& a, const Part& b) {
    const uint32_t offset = a.mesh.nextVertex();
    a.mesh.positions.insert(a.mesh.positions.end(), b.mesh.positions.begin(), b.mesh.positions.end());
    a.mesh.normals.insert(a.mesh.normals.end(), b.mesh.normals.begin(), b.mesh.normals.end());
    for (uint32_t v : b.mesh.indices) a.mesh.indices.push_back(v + offset);
    a.points.positions.insert(a.points.positions.end(), b.points.positions.begin(), b.points.positions.end());
    a.points.normals.insert(a.points.normals.end(), b.points.normals.begin(), b.points.normals.end());
}

ImageAgreement agreement(const Part& whole, const Part& parts, const Camera& camera) {
    return compareImages(renderSurface(whole.mesh, whole.points, camera).image,
                         renderSurface(parts.mesh, parts.points, camera).image);
}

// The slabs in front: their coverage, merged once before the slab's first node; afterwards
// the slab's own coverage is kept for the slabs behind it.
class FrontCoverage final : public CoverageExchange {
public:
    std::vector<uint64_t> front, made;
    void between(OcclusionPyramid& pyramid, int64_t) override {
        if (merged || front.empty()) return;
        pyramid.coverTiles(front);
        pyramid.propagate();
        merged = true;
    }
    void ended(const OcclusionPyramid& pyramid) override { made.assign(pyramid.tiles().begin(), pyramid.tiles().end()); }

private:
    bool merged = false;
};

class ViewParts : public ::testing::Test {
protected:
    void SetUp() override {
        SynthParams p;
        p.kind = SynthKind::Head;
        p.dims = {96, 96, 96};
        source = test::synthBrickSource(p, 16);
        const VolumeInfo& v = source->volume();
        camera = presetCamera(ViewPreset::Normal, v.origin, v.worldMax(), 400, 400);
        whole.stats = extractViewDependent(*source, camera, ViewExtractOptions::sage(kHeadSkinIso), whole.mesh,
                                           whole.points);
    }
    std::unique_ptr<test::MemoryBrickSource> source;
    Camera camera;
    Part whole;
};

TEST_F(ViewParts, ImageColumnsMakeTheWholePicture) {
    const std::vector<int> columns = stripColumns(*source, camera, kHeadSkinIso, 3, 0, camera.width);
    ASSERT_EQ(columns.size(), 4u);
    Part all;
    int64_t bricks = 0;
    for (int k = 0; k < 3; ++k) {
        Part part;
        ViewExtractOptions o = ViewExtractOptions::sage(kHeadSkinIso);
        o.columnBegin = columns[size_t(k)];
        o.columnEnd = columns[size_t(k) + 1];
        o.threads = k == 1 ? 2 : 1;  // a part split again into strips
        part.stats = extractViewDependent(*source, camera, o, part.mesh, part.points);
        EXPECT_GT(part.stats.triangles, 0u) << "part " << k;
        EXPECT_LT(part.stats.bricksActive, whole.stats.bricksActive) << "part " << k << " reads only its share";
        bricks += part.stats.bricksActive;
        append(all, part);
    }
    EXPECT_GE(bricks, whole.stats.bricksActive);
    const ImageAgreement a = agreement(whole, all, camera);
    EXPECT_GE(a.agreement(), 0.995) << a.missing << " missing, " << a.differentColour << " off colour";
}

TEST_F(ViewParts, DepthSlabsWithCoverageFromTheFrontMakeTheWholePicture) {
    const DepthSlabs slabs = depthSlabs(*source, camera, kHeadSkinIso, 3);
    ASSERT_EQ(slabs.count(), 3);
    const VolumeInfo& v = source->volume();
    const BrickLayout& layout = source->layout();
    // Front to back: by distance from the eye's slab.
    std::vector<int> order{0, 1, 2};
    std::stable_sort(order.begin(), order.end(),
                     [&](int a, int b) { return std::abs(a - slabs.eyeSlab) < std::abs(b - slabs.eyeSlab); });
    for (bool exchange : {true, false}) {
        std::vector<FrontCoverage> coverage(3);
        Part all;
        int64_t bricks = 0;
        for (int s : order) {
            const BrickRegion region = slabs.region(s, layout);
            EXPECT_LT(region.lo[slabs.axis], region.hi[slabs.axis]) << "slab " << s << " has layers";
            for (int f = 0; f < 3; ++f) {
                if (!slabs.inFront(f, s) || !exchange) continue;
                if (coverage[size_t(s)].front.empty()) coverage[size_t(s)].front.assign(coverage[size_t(f)].made.size(), 0);
                for (size_t t = 0; t < coverage[size_t(f)].made.size(); ++t)
                    coverage[size_t(s)].front[t] |= coverage[size_t(f)].made[t];
            }
            Part part;
            ViewExtractOptions o = ViewExtractOptions::sage(kHeadSkinIso);
            o.region = &region;
            o.coverage = &coverage[size_t(s)];
            part.stats = extractViewDependent(*source, camera, o, part.mesh, part.points);
            EXPECT_GT(part.stats.view.culledByRegion, 0) << "slab " << s;
            // Its surface lies in its slab.
            const double lo = v.origin[slabs.axis] + double(region.lo[slabs.axis] * layout.brickSize) * v.spacing[slabs.axis];
            const double hi = v.origin[slabs.axis] + double(region.hi[slabs.axis] * layout.brickSize) * v.spacing[slabs.axis];
            for (const glm::vec3& p : part.mesh.positions) {
                ASSERT_GE(p[slabs.axis], lo - 1e-3) << "slab " << s;
                ASSERT_LE(p[slabs.axis], hi + 1e-3) << "slab " << s;
            }
            bricks += part.stats.bricksActive;
            append(all, part);
        }
        const ImageAgreement a = agreement(whole, all, camera);
        EXPECT_GE(a.agreement(), 0.995) << (exchange ? "with" : "without") << " coverage exchange: " << a.missing
                                        << " missing, " << a.differentColour << " off colour";
        // The slabs behind read what the front hides only without the coverage from the front
        // (here 83 bricks with it, as many as the single extraction; 119 without).
        if (exchange) {
            EXPECT_LT(double(bricks), 1.25 * double(whole.stats.bricksActive));
        } else {
            EXPECT_GT(double(bricks), 1.25 * double(whole.stats.bricksActive));
        }
    }
}

TEST_F(ViewParts, SlabsCutBetweenLayersWithEveryLayerOnce) {
    for (int parts : {1, 2, 5, 6, 9}) {  // 96 samples in bricks of 16: 6 layers per axis
        const DepthSlabs slabs = depthSlabs(*source, camera, kHeadSkinIso, parts);
        ASSERT_EQ(slabs.count(), parts);
        EXPECT_EQ(slabs.cuts.front(), 0);
        EXPECT_EQ(slabs.cuts.back(), source->layout().brickCounts[slabs.axis]);
        for (int s = 0; s < parts; ++s) {
            EXPECT_LE(slabs.cuts[size_t(s)], slabs.cuts[size_t(s) + 1]);
            if (parts <= 6) {
                EXPECT_LT(slabs.cuts[size_t(s)], slabs.cuts[size_t(s) + 1]) << parts << " slabs";
            }
            EXPECT_FALSE(slabs.inFront(s, s));
            EXPECT_FALSE(slabs.inFront(s, slabs.eyeSlab));
        }
    }
}

TEST_F(ViewParts, RefusesWhatCannotBeShared) {
    TriangleMesh mesh;
    PointSet points;
    ViewExtractOptions o = ViewExtractOptions::sage(kHeadSkinIso);
    o.columnBegin = 300;
    o.columnEnd = 300;
    EXPECT_THROW(extractViewDependent(*source, camera, o, mesh, points), std::invalid_argument);
    o.columnEnd = 401;
    EXPECT_THROW(extractViewDependent(*source, camera, o, mesh, points), std::invalid_argument);
    o = ViewExtractOptions::sage(kHeadSkinIso);
    FrontCoverage coverage;
    o.coverage = &coverage;
    o.threads = 2;
    EXPECT_THROW(extractViewDependent(*source, camera, o, mesh, points), std::invalid_argument);
}

}  // namespace
}  // namespace vdiso
