// Levels of detail (core/brick_levels.h): the min/max tree's ranges hold every finer level's,
// nodes are the bricks of the levels they say, views at --lod-error 1 look like the
// full-resolution surface at every distance while reading less, a store of format version 2
// still opens and extracts as before, and what the tools refuse. (Coarse samples against a
// brute-force downsample and round trips of every level: test_store.cpp.)
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <optional>

#include "cache/brick_cache.h"
#include "core/camera.h"
#include "core/extract/extract_full.h"
#include "core/extract/extract_view.h"
#include "core/lod/level_source.h"
#include "core/trees/minmax_tree.h"
#include "core/synth/synth.h"
#include "core/view_presets.h"
#include "io/crc32.h"
#include "io/store/brick_store.h"
#include "io/render/image_compare.h"
#include "io/render/renderer.h"
#include "io/store/store_format.h"
#include "io/store/store_writer.h"
#include "io/readers/volume_open.h"
#include "tests/extract_test_util.h"
#include "tests/test_util.h"

namespace vdiso {
namespace {

std::string writeStore(SliceReader& source, const std::string& path, int brickSize, int coarseLevels) {
    StoreWriteOptions o;
    o.brickSize = brickSize;
    o.coarseLevels = coarseLevels;
    writeBrickStore(source, path, o);
    return path;
}

std::string headStore(const test::ScratchDir& dir, const Dims3& dims, int brickSize,
                      int coarseLevels = StoreWriteOptions::kLevelsUntilOneBrick) {
    SynthParams p;
    p.kind = SynthKind::Head;
    p.dims = dims;
    return writeStore(*openSynthVolume(p), dir.file("head.vdiso"), brickSize, coarseLevels);
}

// Level-l brick c covers level-0 bricks [c 2^l, (c+1) 2^l) per axis, clipped to the grid.
TEST(Levels, TreeNodesAreTheLevelsBricksAndTheirRangesHoldEveryFinerLevel) {
    test::ScratchDir dir;
    const BrickStoreReader store(headStore(dir, {70, 66, 37}, 8));
    const std::vector<BrickLevel>& levels = store.levels();
    ASSERT_EQ(levels.size(), 5u);  // 9 x 9 x 5 bricks: one brick at level 4
    std::vector<BrickRange> ranges;
    for (const BrickEntry& e : store.index()) ranges.push_back({e.minValue, e.maxValue});
    const MinMaxTree tree(levels, ranges);
    std::vector<int> bricksAsNodes(levels.size(), 0), nodesAsBricks(levels.size(), 0);
    for (const MinMaxNode& node : tree.nodes()) {
        for (size_t l = 0; l < levels.size(); ++l) nodesAsBricks[l] += node.isBrickOfLevel(int(l));
        for (size_t l = 0; l < levels.size(); ++l) {
            const BrickLayout& layout = levels[l].layout;
            for (int64_t id = 0; id < layout.brickCount(); ++id) {
                const Dims3 c = layout.brickCoord(id);
                bool inside = true, same = true;
                for (int a = 0; a < 3; ++a) {
                    const int64_t lo = c[a] << l, hi = std::min((c[a] + 1) << l, levels[0].layout.brickCounts[a]);
                    inside = inside && lo >= node.lo[a] && hi <= node.hi[a];
                    same = same && lo == node.lo[a] && hi == node.hi[a];
                }
                const BrickRange r = ranges[size_t(levels[l].firstBrick + id)];
                if (inside) {
                    EXPECT_LE(node.minValue, r.minValue) << "level " << l << " brick " << id;
                    EXPECT_GE(node.maxValue, r.maxValue) << "level " << l << " brick " << id;
                }
                if (same) {
                    EXPECT_TRUE(node.isBrickOfLevel(int(l))) << "level " << l << " brick " << id;
                    EXPECT_EQ(tree.brickOf(node, int(l)), levels[l].firstBrick + id);
                    ++bricksAsNodes[l];
                }
            }
        }
    }
    // Every brick of every level is a node, and a node says it is a brick only when it is one.
    for (size_t l = 0; l < levels.size(); ++l) {
        EXPECT_EQ(bricksAsNodes[l], levels[l].layout.brickCount()) << "level " << l;
        EXPECT_EQ(nodesAsBricks[l], levels[l].layout.brickCount()) << "level " << l;
    }
}

// Rendered like the full-resolution octree surface from cameras ever farther away, while the
// far views read coarse bricks and fewer bytes.
struct DistanceResult {
    double agreement;
    uint64_t referenceCovered, missing, differentColour;
    uint64_t dark;  // lit in the reference (a channel >= 80), drawn nearly black (every channel < 40)
    int64_t coarseBricks, thinPartPoints;
    uint64_t bytesRead, bytesReadFull;
};

// The full-resolution octree surface, the reference every view is compared with.
TriangleMesh fullSurface(const BrickStoreReader& store, double iso) {
    TriangleMesh full;
    BrickCache cache(store, 256u << 20);
    extractOctree(cache, {iso, 4}, full);
    return full;
}

DistanceResult viewAtDistance(const BrickStoreReader& store, const TriangleMesh& full, double iso, double scale,
                              int imageSize, bool wise = false, bool points = true) {
    const VolumeInfo& v = store.volume();
    Camera camera = presetCamera(ViewPreset::Normal, v.origin, v.worldMax(), imageSize, imageSize);
    camera.eye = camera.target + (camera.eye - camera.target) * scale;
    camera.zNear = camera.zFar = 0;
    fitClipPlanes(camera, v.origin, v.worldMax());
    DistanceResult r{};
    ViewExtractOptions o = wise ? ViewExtractOptions::wise(iso) : ViewExtractOptions::sage(iso);
    o.points = points;
    TriangleMesh flat, lod;
    PointSet flatPoints, lodPoints;
    {
        BrickCache cache(store, 256u << 20);
        extractViewDependent(cache, camera, o, flat, flatPoints);
        r.bytesReadFull = cache.counters().bytesRead;
    }
    o.lodError = 1;
    BrickCache cache(store, 256u << 20);
    const ExtractStats s = extractViewDependent(cache, camera, o, lod, lodPoints);
    r.bytesRead = cache.counters().bytesRead;
    r.coarseBricks = s.view.coarseBricks;
    r.thinPartPoints = s.view.thinPartPoints;
    const RgbaImage reference = renderSurface(full, PointSet{}, camera).image;
    const RgbaImage picture = renderSurface(lod, lodPoints, camera).image;
    const ImageAgreement a = compareImages(reference, picture);
    const uint8_t* background = reference.rgba.data();  // a corner: the volume is in the middle
    for (size_t i = 0; i < reference.rgba.size(); i += 4) {
        auto brightest = [&](const RgbaImage& m) { return std::max({m.rgba[i], m.rgba[i + 1], m.rgba[i + 2]}); };
        const bool drawn = !std::equal(picture.rgba.begin() + long(i), picture.rgba.begin() + long(i) + 3, background);
        r.dark += brightest(reference) >= 80 && drawn && brightest(picture) < 40;
    }
    r.agreement = a.agreement();
    r.referenceCovered = a.referenceCovered;
    r.missing = a.missing;
    r.differentColour = a.differentColour;
    return r;
}

// `smooth`: the surface's normals vary little within a coarse cell (a head's skin), so the
// coarse picture's colours match too. Elsewhere (bone, noise, an MRI's skin) a coarse vertex's
// normal is the gradient of the filtered field, the average of the fine normals it stands
// for, where the fine picture shows one of them per pixel: the pixels are covered, their
// shading differs beyond the 24/255 the comparison allows, and only coverage is asserted.
void expectFaithfulAtEveryDistance(const BrickStoreReader& store, double iso, const char* what, bool smooth) {
    // 1: the normal view (cells about a pixel: level 0); then ever farther, to where the
    // volume is a few dozen pixels across and its coarsest levels are drawn.
    const TriangleMesh full = fullSurface(store, iso);
    for (double scale : {1.0, 2.5, 5.0, 10.0}) {
        const DistanceResult r = viewAtDistance(store, full, iso, scale, 600);
        const std::string label = std::string(what) + " at " + std::to_string(scale) + "x of " +
                                  std::to_string(r.referenceCovered) + " pixels: " + std::to_string(r.missing) +
                                  " missing, " + std::to_string(r.differentColour) + " of another colour";
        // Missing pixels are silhouette pixels (a coarse surface's outline is a little inside):
        // a larger share of a small picture.
        EXPECT_LE(double(r.missing), (scale <= 5.0 ? 0.01 : 0.02) * double(r.referenceCovered)) << label;
        if (scale <= 2.5 || smooth) {
            EXPECT_GE(r.agreement, scale <= 2.5 ? 0.995 : 0.98) << label;
        }
        EXPECT_LE(r.bytesRead, r.bytesReadFull) << label;
        if (scale >= 5.0) {
            EXPECT_GT(r.coarseBricks, 0) << label;
            EXPECT_LT(double(r.bytesRead), 0.5 * double(r.bytesReadFull)) << label;
        }
    }
}

TEST(Levels, GeneratedHeadLooksTheSameAtEveryDistance) {
    test::ScratchDir dir;
    const BrickStoreReader store(headStore(dir, {192, 192, 192}, 8));
    expectFaithfulAtEveryDistance(store, kHeadSkinIso, "head skin", true);
    expectFaithfulAtEveryDistance(store, kHeadBoneIso, "head bone", false);
}

// WISE takes its levels the same way (its own switches: exact boxes, top-down insertion).
TEST(Levels, WiseUsesTheLevelsToo) {
    test::ScratchDir dir;
    const BrickStoreReader store(headStore(dir, {192, 192, 192}, 8));
    const DistanceResult r = viewAtDistance(store, fullSurface(store, kHeadSkinIso), kHeadSkinIso, 5.0, 600, true);
    EXPECT_GT(r.coarseBricks, 0);
    EXPECT_LT(double(r.bytesRead), 0.5 * double(r.bytesReadFull));
    EXPECT_LE(double(r.missing), 0.01 * double(r.referenceCovered)) << r.missing << " of " << r.referenceCovered;
    EXPECT_GE(r.agreement, 0.98);
}

TEST(Levels, TurbulenceLooksTheSameAtEveryDistance) {
    test::ScratchDir dir;
    SynthParams p;
    p.kind = SynthKind::Turbulence;
    p.dims = {160, 160, 160};
    const BrickStoreReader store(writeStore(*openSynthVolume(p), dir.file("t.vdiso"), 8,
                                            StoreWriteOptions::kLevelsUntilOneBrick));
    expectFaithfulAtEveryDistance(store, turbulenceIso(ScalarType::U16), "turbulence", false);
}

TEST(Levels, RealMriLooksTheSameAtEveryDistance) {
    const std::string path = test::dataFile("ch2.nii.gz");
    if (path.empty())
        GTEST_SKIP() << "VDISO_DATA_DIR has no ch2.nii.gz (scripts/test.sh fetches it)";
    test::ScratchDir scratch;
    auto mri = openVolume(path, {});
    const BrickStoreReader store(writeStore(*mri, scratch.file("mri.vdiso"), 8,
                                            StoreWriteOptions::kLevelsUntilOneBrick));
    expectFaithfulAtEveryDistance(store, 40.5, "mri skin", false);
}

// A tilted plate one voxel thick, in front of a ball: the levels' filter averages it below the
// isovalue, so whole coarse bricks lose it; such a level is not taken for them (they descend),
// and the plate stays at a distance (without that, 186 of its 546 pixels went at 10x).
TEST(Levels, ThinPlateStaysAtADistance) {
    test::ScratchDir dir;
    const Dims3 dims{96, 96, 96};
    test::MemoryVolume volume(dims, ScalarType::U16);
    test::fillBallBesidePlate(volume);
    const BrickStoreReader store(writeStore(volume, dir.file("plate.vdiso"), 8, StoreWriteOptions::kLevelsUntilOneBrick));
    const TriangleMesh full = fullSurface(store, 550);
    for (double scale : {10.0, 20.0}) {
        const DistanceResult r = viewAtDistance(store, full, 550, scale, 600);
        const std::string label = "at " + std::to_string(scale) + "x: " + std::to_string(r.missing) + " of " +
                                  std::to_string(r.referenceCovered) + " pixels missing";
        EXPECT_GT(r.coarseBricks, 0) << label;
        EXPECT_LE(double(r.missing), 0.01 * double(r.referenceCovered)) << label;
        EXPECT_EQ(r.dark, 0u) << label;
        EXPECT_LE(r.bytesRead, r.bytesReadFull) << label;
    }
}

// The Debian CT's head holder, a curved shell one or two voxels thick beside the skull: at ten
// times the normal distance the coarse levels keep it only in strips, and the points for thin
// parts (core/lod/thin_parts.h) fill it in without reading a finer brick. Without them 16 % of
// the bone's pixels went (bench/log.md).
TEST(Levels, RealCtKeepsItsThinPartsAtADistance) {
    const std::string path = test::dataFile("cranium.nhdr");
    if (path.empty()) GTEST_SKIP() << "VDISO_DATA_DIR has no cranium.nhdr (scripts/test.sh fetches it)";
    test::ScratchDir scratch;
    auto ct = openVolume(path, {});
    const BrickStoreReader store(writeStore(*ct, scratch.file("ct.vdiso"), 32, StoreWriteOptions::kLevelsUntilOneBrick));
    const TriangleMesh full = fullSurface(store, 200.5);
    const DistanceResult kept = viewAtDistance(store, full, 200.5, 10.0, 800);
    const DistanceResult lost = viewAtDistance(store, full, 200.5, 10.0, 800, false, false);
    const std::string label = std::to_string(kept.missing) + " of " + std::to_string(kept.referenceCovered) +
                              " pixels missing with points for thin parts (" + std::to_string(kept.thinPartPoints) +
                              "), " + std::to_string(lost.missing) + " without; " + std::to_string(kept.dark) +
                              " drawn dark where the full surface is lit";
    EXPECT_GT(kept.thinPartPoints, 0) << label;
    // The head holder's shell folds at the coarse levels; its vertices facing away were drawn
    // black at 16 pixels (core/mesh.h splitVerticesFacingAway).
    EXPECT_EQ(kept.dark, 0u) << label;
    EXPECT_GT(double(lost.missing), 0.05 * double(lost.referenceCovered)) << label;
    EXPECT_LE(double(kept.missing), 0.01 * double(kept.referenceCovered)) << label;
    EXPECT_LT(double(kept.bytesRead), 0.5 * double(kept.bytesReadFull)) << label;
}

// A fold: two triangles on one edge, the first facing the eye, the second away from it, their
// shared vertices' normals along the second's face. Lit from the eye with two-sided lighting,
// the first triangle would be drawn black there; its vertices get copies of their own with its
// face normal, and the second triangle (whose normals its back turns to the eye) keeps its own.
TEST(Levels, AFoldsVerticesFacingAwayGetCopiesOfTheirOwn) {
    TriangleMesh mesh;
    mesh.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0.5f, 0.5f, -1}};
    const glm::vec3 eye(0.2f, 0.2f, 5);
    mesh.indices = {0, 1, 2, 0, 3, 1};  // the first faces +z, the eye; the second faces down
    const glm::vec3 away = glm::normalize(glm::cross(mesh.positions[3] - mesh.positions[0],
                                                     mesh.positions[1] - mesh.positions[0]));
    ASSERT_LT(glm::dot(away, eye - mesh.positions[3]), 0.0f);
    mesh.normals.assign(4, away);
    const size_t copies = splitVerticesFacingAway(mesh, 0, eye);
    EXPECT_EQ(copies, 3u);  // the first triangle's three vertices
    ASSERT_EQ(mesh.vertexCount(), 7u);
    for (int k = 0; k < 3; ++k) {
        const uint32_t v = mesh.indices[size_t(k)];
        EXPECT_GE(v, 4u);
        EXPECT_EQ(mesh.positions[v], mesh.positions[size_t(k)]);
        EXPECT_GT(glm::dot(mesh.normals[v], eye - mesh.positions[v]), 0.0f);
    }
    EXPECT_EQ(std::vector<uint32_t>(mesh.indices.begin() + 3, mesh.indices.end()), (std::vector<uint32_t>{0, 3, 1}));
    EXPECT_EQ(splitVerticesFacingAway(mesh, 0, eye), 0u);  // nothing left to split
}

// Where neighbouring bricks are extracted at different levels, their surfaces meet the shared
// face along different curves; the caps (core/lod/face_cap.h) close the slivers between them. At
// a large error, so that levels change within the view, caps are made where levels meet, the
// capped picture misses no more of the full surface's pixels than the open one, and agrees
// with the full surface. (On the 2560^3 head's normal view at 1 px, the open seams let the
// background through at 4 of 169,029 pixels, the capped ones at none: bench/log.md.)
TEST(Levels, CapsCloseTheSeamsBetweenLevels) {
    test::ScratchDir dir;
    const BrickStoreReader store(headStore(dir, {192, 192, 192}, 8));
    const VolumeInfo& v = store.volume();
    Camera camera = presetCamera(ViewPreset::Normal, v.origin, v.worldMax(), 600, 600);
    TriangleMesh full;
    BrickCache cache(store, 256u << 20);
    extractOctree(cache, {kHeadSkinIso, 4}, full);
    const RenderResult reference = renderSurface(full, PointSet{}, camera);
    ImageAgreement agreement[2];
    for (const bool cap : {false, true}) {
        ViewExtractOptions o = ViewExtractOptions::sage(kHeadSkinIso);
        o.lodError = 4;
        o.capSeams = cap;
        TriangleMesh mesh;
        PointSet points;
        const ExtractStats s = extractViewDependent(cache, camera, o, mesh, points);
        EXPECT_GT(s.view.coarseBricks, 0);
        EXPECT_LT(s.view.coarseBricks, s.bricksActive);  // levels meet in this view
        EXPECT_EQ(s.view.cappedFaces > 0, cap);
        agreement[cap] = compareImages(reference.image, renderSurface(mesh, points, camera).image);
    }
    const std::string label = "open: " + std::to_string(agreement[0].missing) + " missing, capped: " +
                              std::to_string(agreement[1].missing) + " missing of " +
                              std::to_string(agreement[1].referenceCovered);
    EXPECT_LE(agreement[1].missing, agreement[0].missing) << label;
    EXPECT_GE(agreement[1].agreement(), 0.995) << label;
}

// A store written before levels of detail (format version 2: no level count, level 0's bricks
// alone) opens, has one level, and extracts what it did; asking it for levels changes nothing.
TEST(Levels, VersionTwoStoreOpensAndExtractsAsBefore) {
    test::ScratchDir dir;
    const std::string path = headStore(dir, {64, 60, 56}, 8, 0);
    auto bytes = test::rewriteStoreIndex(test::readFile(path), [](std::vector<unsigned char>&) {}, false);
    const uint32_t two = 2, none = 0;
    std::memcpy(bytes.data() + 8, &two, 4);
    std::memcpy(bytes.data() + 108, &none, 4);  // the level count was reserved, zero
    const uint32_t crc = crc32Of(bytes.data(), 160);
    std::memcpy(bytes.data() + 160, &crc, 4);
    const std::string old = dir.file("old.vdiso");
    test::writeFile(old, bytes.data(), bytes.size());

    const BrickStoreReader current(path), before(old);
    EXPECT_EQ(before.header().formatVersion, 2u);
    EXPECT_EQ(before.header().levelCount, 1);
    EXPECT_EQ(before.levels().size(), 1u);
    BrickCache a(current, 64u << 20), b(before, 64u << 20);
    TriangleMesh ma, mb;
    extractOctree(a, {kHeadSkinIso, 4}, ma);
    extractOctree(b, {kHeadSkinIso, 4}, mb);
    EXPECT_EQ(ma.positions, mb.positions);
    EXPECT_EQ(ma.indices, mb.indices);
    const VolumeInfo& v = before.volume();
    const Camera camera = presetCamera(ViewPreset::Distant, v.origin, v.worldMax(), 400, 400);
    ViewExtractOptions o = ViewExtractOptions::sage(kHeadSkinIso);
    TriangleMesh flat, lod;
    PointSet pf, pl;
    extractViewDependent(b, camera, o, flat, pf);
    o.lodError = 1;
    const ExtractStats s = extractViewDependent(b, camera, o, lod, pl);
    EXPECT_EQ(s.view.coarseBricks, 0);
    EXPECT_EQ(flat.positions, lod.positions);
    EXPECT_EQ(pf.positions, pl.positions);
}

// A level count the volume cannot have (none, or more than until one brick) is refused at open,
// naming the file; so is a version-3 header whose brick count leaves out a level's bricks.
TEST(Levels, ImpossibleLevelCountsAreRefused) {
    test::ScratchDir dir;
    const std::string path = headStore(dir, {40, 40, 40}, 8);  // 5 bricks a side: 4 levels
    const auto good = test::readFile(path);
    auto openWith = [&](uint32_t levels, std::optional<uint64_t> bricks = std::nullopt) {
        auto bytes = good;
        std::memcpy(bytes.data() + 108, &levels, 4);
        if (bricks) std::memcpy(bytes.data() + 112, &*bricks, 8);
        const uint32_t crc = crc32Of(bytes.data(), 160);
        std::memcpy(bytes.data() + 160, &crc, 4);
        const std::string bad = dir.file("bad.vdiso");
        test::writeFile(bad, bytes.data(), bytes.size());
        try {
            BrickStoreReader reader(bad);
        } catch (const std::exception& e) {
            return std::string(e.what());
        }
        return std::string();
    };
    EXPECT_EQ(openWith(4), "");
    for (const uint32_t levels : {0u, 5u, 4000000000u}) {
        const std::string error = openWith(levels);
        EXPECT_NE(error.find("bad.vdiso: header's level count " + std::to_string(levels) + " is invalid"),
                  std::string::npos)
            << error;
    }
    EXPECT_NE(openWith(4, 125).find("bad.vdiso: header's brick count does not match"), std::string::npos);
}

// --level L extracts level L's whole surface: the same as a store whose level 0 is level L's
// samples.
TEST(Levels, FullExtractionAtACoarseLevelIsThatLevelsSurface) {
    test::ScratchDir dir;
    const BrickStoreReader store(headStore(dir, {50, 47, 44}, 8));
    BrickCache cache(store, 64u << 20);
    LevelSource level1(cache, 1);
    EXPECT_EQ(level1.volume().dims, (Dims3{26, 24, 23}));
    EXPECT_EQ(level1.volume().spacing, store.volume().spacing * 2.0);
    TriangleMesh coarse, fine;
    extractOctree(level1, {kHeadSkinIso, 4}, coarse);
    extractOctree(cache, {kHeadSkinIso, 4}, fine);
    EXPECT_GT(coarse.triangleCount(), fine.triangleCount() / 8);
    EXPECT_LT(coarse.triangleCount(), fine.triangleCount() / 2);
    EXPECT_EQ(test::checkClosedOriented(coarse, &level1.volume()), "");
}

TEST(Levels, ToolsRefuseLevelsTheStoreDoesNotHave) {
    test::ScratchDir dir;
    const std::string raw = dir.file("v.raw"), out = dir.file("v.vdiso");
    std::vector<uint8_t> samples(20 * 18 * 17, 7);
    test::writeFile(raw, samples.data(), samples.size());
    auto r = test::runVdiso("convert " + raw + " " + out + " --dims 20,18,17 --type u8 --brick 8 --levels 3");
    EXPECT_NE(r.exitCode, 0);
    EXPECT_NE(r.output.find("--levels 3"), std::string::npos) << r.output;
    EXPECT_NE(r.output.find("at most 2 coarser levels"), std::string::npos) << r.output;
    EXPECT_FALSE(std::filesystem::exists(out));
    r = test::runVdiso("convert " + raw + " " + out + " --dims 20,18,17 --type u8 --brick 8 --levels 1");
    ASSERT_EQ(r.exitCode, 0) << r.output;
    r = test::runVdiso("info " + out);
    EXPECT_NE(r.output.find("level 1 "), std::string::npos) << r.output;
    r = test::runVdiso("extract " + out + " --iso 3 --level 2");
    EXPECT_NE(r.exitCode, 0);
    EXPECT_NE(r.output.find("--level 2: " + out + " holds 2 levels of detail"), std::string::npos) << r.output;
    r = test::runVdiso("extract " + out + " --iso 3 --method sage --level 1");
    EXPECT_NE(r.exitCode, 0);
    EXPECT_NE(r.output.find("--level applies to the full methods, octree and noise"), std::string::npos) << r.output;
    r = test::runVdiso("extract " + out + " --iso 3 --lod-error 2");
    EXPECT_EQ(r.exitCode, 2);
    EXPECT_NE(r.output.find("--lod-error applies to the view-dependent methods, sage and wise"), std::string::npos)
        << r.output;
}

}  // namespace
}  // namespace vdiso
