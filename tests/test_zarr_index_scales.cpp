// vdiso index over an OME-Zarr's own scales (io/store/zarr_index.h): scales that fit vdiso's
// levels of detail are read where they lie, not filtered and stored; an index made so opens
// brick for brick as the index that filtered them does when the scales hold vdiso's own filter,
// a scale a sample or two short is clamped at its last sample, scales that do not fit are
// filtered as before and the summary says why, a changed scale chunk is refused by name, and
// an interrupted pass over the scales goes on where it stopped.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>

#include "core/brick_levels.h"
#include "core/camera.h"
#include "core/extract/extract_view.h"
#include "core/lod/downsample.h"
#include "core/view_presets.h"
#include "cache/brick_cache.h"
#include "io/error.h"
#include "io/store/brick_store.h"
#include "io/store/external_bricks.h"
#include "io/store/zarr_index.h"
#include "tests/mesh_test_readers.h"
#include "tests/reader_test_util.h"
#include "tests/test_util.h"
#include "tests/zarr_test_util.h"

namespace vdiso {
namespace {

using test::expectIoError;

const Dims3 kDims{45, 41, 38};
constexpr double kIso = 900.5;

// Two overlapping blobs: their surface at kIso crosses every level's bricks.
double blobs(int64_t x, int64_t y, int64_t z) {
    const double a = std::hypot(x - 17.5, y - 20.2, z - 16.1), b = std::hypot(x - 30.3, y - 18.7, z - 22.4);
    return std::clamp(1800.0 - 60.0 * std::min(a, b * 1.2) + 90.0 * std::sin(x * 0.37 + z * 0.21), 0.0, 65535.0);
}

// Levels 0 .. count-1 of `blobs` as vdiso makes them (core/lod/downsample.h), x fastest.
std::vector<std::vector<uint16_t>> tentLevels(int count) {
    std::vector<std::vector<uint16_t>> levels(1);
    for (int64_t z = 0; z < kDims[2]; ++z)
        for (int64_t y = 0; y < kDims[1]; ++y)
            for (int64_t x = 0; x < kDims[0]; ++x) levels[0].push_back(uint16_t(std::lround(blobs(x, y, z))));
    for (int l = 1; l < count; ++l) {
        const Dims3 fine = levelDims(kDims, l - 1), coarse = levelDims(kDims, l);
        const std::vector<uint16_t>& f = levels.back();
        std::vector<uint16_t> c(size_t(coarse[0] * coarse[1] * coarse[2]));
        auto slice = [&](int64_t z) { return f.data() + std::clamp<int64_t>(z, 0, fine[2] - 1) * fine[0] * fine[1]; };
        for (int64_t z = 0; z < coarse[2]; ++z)
            downsampleRows<uint16_t>(slice(2 * z - 1), slice(2 * z), slice(2 * z + 1), fine, coarse, 0, coarse[1],
                                     c.data() + z * coarse[0] * coarse[1]);
        levels.push_back(std::move(c));
    }
    return levels;
}

// One scale of an image: its array and where its samples stand ("scale" factor of level 0's
// spacing, and a translation in level-0 samples).
struct Scale {
    test::ArraySpec array;
    glm::dvec3 factor{1.0};
    double shift = 0;
};

// An OME-Zarr image of `scales` at `root` (v0.4 on Zarr v2, or v0.5 on v3), level 0's spacing
// (x, y, z) 0.5, 0.75, 2.
void writeImage(const std::filesystem::path& root, int format, const std::vector<Scale>& scales) {
    const glm::dvec3 spacing{0.5, 0.75, 2.0};
    std::string datasets;
    for (size_t i = 0; i < scales.size(); ++i) {
        test::ArraySpec a = scales[i].array;
        a.format = format;
        a.separator = format == 3 ? '/' : '.';
        test::writeArray(root / std::to_string(i), a);
        const glm::dvec3 s = spacing * scales[i].factor, t = spacing * scales[i].shift;
        datasets += std::string(i ? ", " : "") + R"({"path": ")" + std::to_string(i) +
                    R"(", "coordinateTransformations": [{"type": "scale", "scale": [)" + std::to_string(s.z) + ", " +
                    std::to_string(s.y) + ", " + std::to_string(s.x) + R"(]}, {"type": "translation", "translation": [)" +
                    std::to_string(t.z) + ", " + std::to_string(t.y) + ", " + std::to_string(t.x) + "]}]}";
    }
    const std::string multiscales = R"([{"version": ")" + std::string(format == 2 ? "0.4" : "0.5") +
                                    R"(", "axes": [{"name": "z", "type": "space"}, {"name": "y", "type": "space"}, )"
                                    R"({"name": "x", "type": "space"}], "datasets": [)" + datasets + "]}]";
    if (format == 2) {
        test::writeFile((root / ".zgroup").string(), R"({"zarr_format": 2})");
        test::writeFile((root / ".zattrs").string(), R"({"multiscales": )" + multiscales + "}");
    } else {
        test::writeFile((root / "zarr.json").string(), R"({"zarr_format": 3, "node_type": "group", "attributes": {"ome": )"
                                                       R"({"version": "0.5", "multiscales": )" + multiscales + "}}}");
    }
}

// Scales 0 .. count-1 holding vdiso's own levels, chunks of 10 (level 0) and 8 samples.
std::vector<Scale> tentScales(int count) {
    const auto levels = std::make_shared<std::vector<std::vector<uint16_t>>>(tentLevels(count));
    std::vector<Scale> scales;
    for (int l = 0; l < count; ++l) {
        Scale s;
        s.array.dims = levelDims(kDims, l);
        s.array.chunk = l ? std::vector<int64_t>{8, 8, 8} : std::vector<int64_t>{10, 10, 10};
        const Dims3 d = s.array.dims;
        s.array.sample = [levels, l, d](int64_t x, int64_t y, int64_t z) {
            return double((*levels)[size_t(l)][size_t((z * d[1] + y) * d[0] + x)]);
        };
        s.factor = glm::dvec3(double(1 << l));
        scales.push_back(std::move(s));
    }
    return scales;
}

ZarrIndexOptions indexOptions(bool ownScales) {  // every scale that fits, or none
    ZarrIndexOptions o;
    o.store.brickSize = 8;  // 45 x 41 x 38 samples: 6 x 5 x 5 bricks, levels 0-3
    o.scaleLevels = ownScales ? 16 : 0;
    return o;
}

class ZarrIndexScales : public test::ReaderFileTest {};

TEST_F(ZarrIndexScales, ScalesThatFitAreReadWhereTheyLie) {
    for (int format : {2, 3}) {
        const std::string name = "img" + std::to_string(format) + ".zarr", what = "Zarr v" + std::to_string(format);
        writeImage(path(name), format, tentScales(3));
        const ZarrIndexSummary own = indexZarr(path(name), path(name) + ".vdiso", indexOptions(true));
        const ZarrIndexSummary made = indexZarr(path(name), path(name + ".made.vdiso"), indexOptions(false));
        EXPECT_EQ(own.ownScaleLevels, 2) << what;
        EXPECT_TRUE(own.scalesNotUsed.empty()) << own.scalesNotUsed;
        EXPECT_EQ(made.ownScaleLevels, 0) << what;
        EXPECT_EQ(own.store.levels, 4) << what;  // level 3 filtered from scale 2
        EXPECT_GT(own.chunks, made.chunks) << what;  // the scales' chunks are pinned too
        const BrickStoreReader a(path(name)), b(path(name + ".made.vdiso"));
        EXPECT_EQ(a.header().formatVersion, 7u) << what;
        EXPECT_EQ(b.header().formatVersion, 6u) << what;
        ASSERT_NE(a.external(), nullptr);
        EXPECT_EQ(a.external()->levelCount(), 3) << what;
        EXPECT_LT(a.fileBytes() * 2, b.fileBytes()) << what;  // no coarse samples but level 3's
        // Scales holding vdiso's filter: the same entries, codes, histogram and samples.
        test::expectSameStore(a, b, what);
        // A distant view draws from the coarse levels: the same triangles, from the scales' chunks.
        const BrickStoreReader fresh(path(name));
        BrickCache ca(fresh, 64u << 20), cb(b, 64u << 20);
        const VolumeInfo& v = a.volume();
        ViewExtractOptions options = ViewExtractOptions::sage(kIso);
        options.lodError = 4;
        const Camera camera = presetCamera(ViewPreset::Distant, v.origin, v.worldMax(), 128, 128);
        TriangleMesh ma, mb;
        PointSet pa, pb;
        const ExtractStats sa = extractViewDependent(ca, camera, options, ma, pa);
        extractViewDependent(cb, camera, options, mb, pb);
        EXPECT_GT(mb.triangleCount(), 20u) << what;
        EXPECT_GT(sa.view.coarseBricks, 0) << what;
        test::expectSameMesh(ma, mb, what + " distant");
    }
    // From the command line: level 1 by default, more by --scale-levels, none by --own-levels.
    auto r = test::runVdiso("index " + path("img2.zarr") + " --brick 8 --index " + path("one.vdiso"));
    ASSERT_EQ(r.exitCode, 0) << r.output;
    EXPECT_NE(r.output.find("level 1 from its own scale 1"), std::string::npos) << r.output;
    test::expectSameStore(BrickStoreReader(path("one.vdiso")), BrickStoreReader(path("img2.zarr.made.vdiso")), "level 1");
    r = test::runVdiso("index " + path("img2.zarr") + " --brick 8 --scale-levels 2 --index " + path("cli.vdiso"));
    ASSERT_EQ(r.exitCode, 0) << r.output;
    EXPECT_NE(r.output.find("levels 1-2 from its own scales"), std::string::npos) << r.output;
    r = test::runVdiso("info " + path("cli.vdiso"));
    EXPECT_NE(r.output.find("levels 0-2's (its own scales)"), std::string::npos) << r.output;
    r = test::runVdiso("index " + path("img2.zarr") + " --brick 8 --own-levels --index " + path("cli2.vdiso"));
    ASSERT_EQ(r.exitCode, 0) << r.output;
    EXPECT_EQ(r.output.find("own scales"), std::string::npos) << r.output;
}

// A scale made by taking every other sample is ceil(n/2) samples long, one short of vdiso's
// level on an even axis: its bricks repeat its last sample there, as the index measured them.
TEST_F(ZarrIndexScales, ShortScalesAreClampedAtTheirLastSample) {
    std::vector<Scale> scales(3);
    for (int l = 0; l < 3; ++l) {
        const int64_t step = int64_t(1) << l;
        for (int a = 0; a < 3; ++a) scales[size_t(l)].array.dims[a] = (kDims[a] + step - 1) / step;
        scales[size_t(l)].array.chunk = {7, 9, 8};
        scales[size_t(l)].array.step = int(step);
        scales[size_t(l)].array.sample = [](int64_t x, int64_t y, int64_t z) { return std::round(blobs(x, y, z)); };
        scales[size_t(l)].factor = glm::dvec3(double(step));
    }
    ASSERT_EQ(scales[1].array.dims[2] + 1, levelDims(kDims, 1)[2]);  // 19 of 20 on z
    writeImage(path("s.zarr"), 2, scales);
    const ZarrIndexSummary s = indexZarr(path("s.zarr"), path("s.zarr.vdiso"), indexOptions(true));
    ASSERT_EQ(s.ownScaleLevels, 2) << s.scalesNotUsed;
    const BrickStoreReader index(path("s.zarr"));
    std::vector<uint16_t> brick(index.brickBytes() / 2);
    for (int l = 1; l <= 2; ++l) {
        const BrickLevel& level = index.levels()[size_t(l)];
        const Dims3& own = scales[size_t(l)].array.dims;
        const int side = level.layout.side();
        for (int64_t id = 0; id < level.layout.brickCount(); ++id) {
            index.readBrick(level.firstBrick + id, brick.data());
            const Dims3 c = level.layout.brickCoord(id);
            auto at = [&](int a, int i) {
                return std::min(level.layout.clampSample(a, level.layout.firstSample(c[a]) + i), own[a] - 1);
            };
            for (int k = 0; k < side; ++k)
                for (int j = 0; j < side; ++j)
                    for (int i = 0; i < side; ++i)
                        ASSERT_EQ(brick[size_t((k * side + j) * side + i)],
                                  uint16_t(std::round(blobs(at(0, i) << l, at(1, j) << l, at(2, k) << l))))
                            << "level " << l << " brick " << id << " sample " << i << "," << j << "," << k;
        }
    }
}

// Scales whose samples stand elsewhere than vdiso's (a translation), or that are not 2x on
// every axis, are not taken: the levels are filtered as without scales, and the summary says
// which scale and why.
TEST_F(ZarrIndexScales, ScalesThatDoNotFitAreFilteredAndSaidSo) {
    std::vector<Scale> shifted = tentScales(3);
    shifted[1].shift = 0.5;
    writeImage(path("t.zarr"), 2, shifted);
    ZarrIndexSummary s = indexZarr(path("t.zarr"), path("t.zarr.vdiso"), indexOptions(true));
    EXPECT_EQ(s.ownScaleLevels, 0);
    EXPECT_NE(s.scalesNotUsed.find("scale 1"), std::string::npos) << s.scalesNotUsed;
    EXPECT_NE(s.scalesNotUsed.find("origin"), std::string::npos) << s.scalesNotUsed;
    indexZarr(path("t.zarr"), path("t.made.vdiso"), indexOptions(false));
    test::expectSameStore(BrickStoreReader(path("t.zarr")), BrickStoreReader(path("t.made.vdiso")), "shifted");

    std::vector<Scale> flat = tentScales(3);
    flat[2].factor.z = 2;  // scale 2 keeps scale 1's z spacing: only scale 1 fits
    writeImage(path("f.zarr"), 3, flat);
    s = indexZarr(path("f.zarr"), path("f.zarr.vdiso"), indexOptions(true));
    EXPECT_EQ(s.ownScaleLevels, 1);
    EXPECT_NE(s.scalesNotUsed.find("scale 2"), std::string::npos) << s.scalesNotUsed;
    EXPECT_NE(s.scalesNotUsed.find("spacing"), std::string::npos) << s.scalesNotUsed;
    indexZarr(path("f.zarr"), path("f.made.vdiso"), indexOptions(false));
    test::expectSameStore(BrickStoreReader(path("f.zarr")), BrickStoreReader(path("f.made.vdiso")), "scale 1 only");
}

// A scale's chunk or metadata changed after indexing is refused by name, as level 0's are.
TEST_F(ZarrIndexScales, ChangedScalesAreRefusedByName) {
    std::vector<Scale> scales = tentScales(3);
    writeImage(path("c.zarr"), 2, scales);
    indexZarr(path("c.zarr"), path("c.zarr.vdiso"), indexOptions(true));
    const std::string chunk = path("c.zarr/1/1.0.0");
    std::string bytes = test::readText(chunk);
    bytes[bytes.size() / 2] ^= 0x10;
    test::writeFile(chunk, bytes);
    {
        const BrickStoreReader index(path("c.zarr"));
        const BrickLevel& level1 = index.levels()[1];
        std::vector<unsigned char> brick(index.brickBytes());
        expectIoError([&] { index.readBrick(level1.firstBrick + level1.layout.brickId(0, 0, 1), brick.data()); },
                      {"c.zarr/1/1.0.0", "changed since it was indexed", "vdiso index"});
        index.readBrick(0, brick.data());  // level 0 as it was
    }
    scales[2].array.chunk = {4, 8, 8};
    writeImage(path("c.zarr"), 2, scales);  // scale 2's metadata changed (and scale 1 written again)
    expectIoError([&] { BrickStoreReader{path("c.zarr")}; }, {"c.zarr.vdiso", "(level 2)", "vdiso index"});
}

// An index pass stopped by a scale's chunk that cannot be decoded goes on from its checkpoint,
// with the scales' pins and places, and writes the very bytes of an uninterrupted run.
TEST_F(ZarrIndexScales, AnInterruptedPassOverScalesGoesOn) {
    writeImage(path("r.zarr"), 2, tentScales(3));
    ZarrIndexOptions o = indexOptions(true);
    o.checkpointSeconds = 0;
    indexZarr(path("r.zarr"), path("whole.vdiso"), o);
    const std::string index = path("r.vdiso"), chunk = path("r.zarr/1/2.1.1");  // scale 1, z 16-19
    const std::string good = test::readText(chunk);
    test::writeFile(chunk, "not blosc");
    expectIoError([&] { indexZarr(path("r.zarr"), index, o); }, {chunk});
    ASSERT_TRUE(std::filesystem::exists(indexCheckpointPath(index)));
    test::writeFile(chunk, good);
    const ZarrIndexSummary s = indexZarr(path("r.zarr"), index, o);
    EXPECT_GT(s.store.resumedLayers, 0);
    EXPECT_TRUE(s.startedOver.empty()) << s.startedOver;
    EXPECT_EQ(test::readText(index), test::readText(path("whole.vdiso")));
    EXPECT_FALSE(std::filesystem::exists(indexCheckpointPath(index)));
}

}  // namespace
}  // namespace vdiso
