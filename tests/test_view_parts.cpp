// One view-dependent extraction shared out in parts, as the ranks of an MPI job share it
// (mpi/): parts of the image (columns), or depth-sorted slabs of the volume that take in the
// coverage of the slabs in front of them. Here the parts run one after another in one process;
// together they must draw the single extraction's picture (agreement at least 99.5%), each
// reading only its share.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdlib>
#include <stdexcept>

#include "core/extract/depth_slabs.h"
#include "core/extract/extract_full.h"
#include "core/extract/extract_view.h"
#include "core/extract/image_strips.h"
#include "core/view_presets.h"
#include "io/render/image_compare.h"
#include "io/render/renderer.h"
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

// The slabs one after another, front to back (by distance from the eye's slab), each taking
// in the coverage of the slabs in front of it (none without `exchange`); returns their output
// together, and the bricks they read in `bricks`.
Part extractBySlabs(test::MemoryBrickSource& source, const Camera& camera, int count, bool exchange,
                    int64_t& bricks, std::vector<uint64_t>* trianglesBySlab = nullptr) {
    const DepthSlabs slabs = depthSlabs(source, camera, kHeadSkinIso, count);
    const VolumeInfo& v = source.volume();
    const BrickLayout& layout = source.layout();
    std::vector<int> order(static_cast<size_t>(count));
    for (int s = 0; s < count; ++s) order[size_t(s)] = s;
    std::stable_sort(order.begin(), order.end(),
                     [&](int a, int b) { return std::abs(a - slabs.eyeSlab) < std::abs(b - slabs.eyeSlab); });
    std::vector<FrontCoverage> coverage(static_cast<size_t>(count));
    Part all;
    bricks = 0;
    if (trianglesBySlab) trianglesBySlab->assign(size_t(count), 0);
    for (int s : order) {
        const BrickRegion region = slabs.region(s, layout);
        EXPECT_LT(region.lo[slabs.axis], region.hi[slabs.axis]) << "slab " << s << " has layers";
        for (int f = 0; f < count; ++f) {
            if (!slabs.inFront(f, s) || !exchange) continue;
            std::vector<uint64_t>& front = coverage[size_t(s)].front;
            if (front.empty()) front.assign(coverage[size_t(f)].made.size(), 0);
            for (size_t t = 0; t < coverage[size_t(f)].made.size(); ++t) front[t] |= coverage[size_t(f)].made[t];
        }
        Part part;
        ViewExtractOptions o = ViewExtractOptions::sage(kHeadSkinIso);
        o.region = &region;
        o.coverage = &coverage[size_t(s)];
        part.stats = extractViewDependent(source, camera, o, part.mesh, part.points);
        EXPECT_GT(part.stats.view.culledByRegion, 0) << "slab " << s;
        // Its surface lies in its slab.
        const double lo = v.origin[slabs.axis] + double(region.lo[slabs.axis] * layout.brickSize) * v.spacing[slabs.axis];
        const double hi = v.origin[slabs.axis] + double(region.hi[slabs.axis] * layout.brickSize) * v.spacing[slabs.axis];
        for (const glm::vec3& p : part.mesh.positions) {
            EXPECT_GE(p[slabs.axis], lo - 1e-3) << "slab " << s;
            EXPECT_LE(p[slabs.axis], hi + 1e-3) << "slab " << s;
            if (p[slabs.axis] < lo - 1e-3 || p[slabs.axis] > hi + 1e-3) break;
        }
        bricks += part.stats.bricksActive;
        if (trianglesBySlab) (*trianglesBySlab)[size_t(s)] = part.mesh.triangleCount();
        append(all, part);
    }
    return all;
}

TEST_F(ViewParts, DepthSlabsWithCoverageFromTheFrontMakeTheWholePicture) {
    for (bool exchange : {true, false}) {
        int64_t bricks = 0;
        const Part all = extractBySlabs(*source, camera, 3, exchange, bricks);
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

// The eye inside the volume, in the middle slab, with a wide view reaching behind the eye's
// plane: slabs on both sides show, and each takes coverage only from its own side.
TEST_F(ViewParts, DepthSlabsWithTheEyeInsideTheVolume) {
    const VolumeInfo& v = source->volume();
    // The slabs' cuts depend on the view's axis (x here), not on the eye: the eye goes in slab
    // 1, a cell and a half past its cut with slab 0, so that the view's edge reaches slab 0's
    // surface.
    Camera inside = camera;
    inside.target = inside.eye + glm::dvec3(1.0, 0.9, 0.2);
    const DepthSlabs cut = depthSlabs(*source, inside, kHeadSkinIso, 3);
    ASSERT_EQ(cut.axis, 0);
    glm::dvec3 eye = 0.5 * (v.origin + v.worldMax());
    eye.x = v.origin.x + (double(cut.cuts[1]) * source->layout().brickSize + 1.5) * v.spacing.x;
    inside.eye = eye;
    inside.target = eye + glm::dvec3(1.0, 0.9, 0.2);
    inside.fovYDegrees = 110;
    inside.zNear = inside.zFar = 0;
    fitClipPlanes(inside, v.origin, v.worldMax());
    const DepthSlabs slabs = depthSlabs(*source, inside, kHeadSkinIso, 3);
    ASSERT_EQ(slabs.eyeSlab, 1);
    Part single;
    single.stats = extractViewDependent(*source, inside, ViewExtractOptions::sage(kHeadSkinIso), single.mesh,
                                        single.points);
    int64_t bricks = 0;
    std::vector<uint64_t> triangles;
    const Part all = extractBySlabs(*source, inside, 3, true, bricks, &triangles);
    ASSERT_EQ(triangles.size(), 3u);
    // Nothing behind the eye or the near plane is made, and nothing in view is lost: the
    // whole surface draws the same picture.
    Part full;
    extractOctree(*source, {kHeadSkinIso, 4}, full.mesh);
    const ImageAgreement f = agreement(full, single, inside);
    EXPECT_GE(f.agreement(), 0.995) << f.missing << " missing, " << f.differentColour << " off colour";
    EXPECT_LT(single.stats.triangles, full.mesh.triangleCount() / 2);
    EXPECT_GT(triangles[0], 0u) << "the slab behind the eye's plane shows at the edges";
    EXPECT_GT(triangles[2], 0u);
    const ImageAgreement a = agreement(single, all, inside);
    EXPECT_GT(a.referenceCovered, 10000u);
    EXPECT_GE(a.agreement(), 0.995) << a.missing << " missing, " << a.differentColour << " off colour";
}

// DepthSlabs::inFront against a walk along the axis from the eye to each slab: slab f may hide
// slab s exactly when the walk from the eye to s crosses f first.
TEST_F(ViewParts, WhichSlabsHideWhichIsTheWalkFromTheEye) {
    const VolumeInfo& v = source->volume();
    const int64_t layers = source->layout().brickCounts[1];
    for (double at : {-0.5, 0.0, 0.3, 0.5, 0.7, 1.0, 1.5}) {  // the eye's place along y, in the volume's depth
        for (int count : {1, 2, 3, 5, 6}) {
            Camera c = camera;
            c.eye = glm::dvec3(0.5, at, 0.5) * (v.worldMax() - v.origin) + v.origin;
            c.target = c.eye + glm::dvec3(0.1, 1.0, 0.1);  // slabs along y
            const DepthSlabs slabs = depthSlabs(*source, c, kHeadSkinIso, count);
            ASSERT_EQ(slabs.axis, 1);
            const double eye = (c.eye.y - v.origin.y) / (v.spacing.y * source->layout().brickSize);
            for (int s = 0; s < count; ++s) {
                const double target = 0.5 * double(slabs.cuts[size_t(s)] + slabs.cuts[size_t(s) + 1]);
                const double eyeClamped = std::clamp(eye, 0.0, double(layers));
                for (int f = 0; f < count; ++f) {
                    // The walk from the eye (clamped into the volume) to slab s's middle crosses slab f
                    // before reaching s.
                    const double lo = double(slabs.cuts[size_t(f)]), hi = double(slabs.cuts[size_t(f) + 1]);
                    const bool crossed = f != s && lo < hi &&
                                         std::min(eyeClamped, target) < hi && std::max(eyeClamped, target) >= lo &&
                                         !(s == slabs.eyeSlab);
                    EXPECT_EQ(slabs.inFront(f, s), crossed) << "eye at " << at << ", " << count << " slabs, " << f
                                                            << " before " << s;
                }
            }
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
