// Sub-block ranges (core/trees/sub_blocks.h): the codes always contain the true range, the store
// keeps them, and view-dependent extraction uses them to read fewer bricks for the same
// surface.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstring>
#include <limits>
#include <random>

#include "cache/brick_cache.h"
#include "core/camera.h"
#include "core/extract/extract_view.h"
#include "core/kernel/iso.h"
#include "core/trees/sub_blocks.h"
#include "core/brick_levels.h"
#include "core/synth/synth.h"
#include "core/view_presets.h"
#include "io/store/brick_store.h"
#include "io/error.h"
#include "io/store/store_writer.h"
#include "io/readers/volume_open.h"
#include "tests/extract_test_util.h"
#include "tests/test_util.h"

namespace vdiso {
namespace {

TEST(SubBlocks, DecodedRangeContainsTheEncodedOne) {
    std::mt19937 rng(5);
    std::uniform_real_distribution<double> unit(0.0, 1.0);
    for (int trial = 0; trial < 200000; ++trial) {
        // Ranges of every scale, integers (u16) and fractions (f32), and degenerate ones.
        const double scale = trial % 3 == 0 ? 65535.0 : trial % 3 == 1 ? 1e-3 : 3e7;
        float a = float((unit(rng) - 0.3) * scale), b = float((unit(rng) - 0.3) * scale);
        if (trial % 2 == 0) {
            a = std::round(a);
            b = std::round(b);
        }
        const BrickRange brick{std::min(a, b), std::max(a, b)};
        double lo = brick.minValue + unit(rng) * (double(brick.maxValue) - brick.minValue);
        double hi = brick.minValue + unit(rng) * (double(brick.maxValue) - brick.minValue);
        if (lo > hi) std::swap(lo, hi);
        if (trial % 7 == 0) lo = brick.minValue;
        if (trial % 11 == 0) hi = brick.maxValue;
        lo = double(float(lo));  // sample values: representable in the brick's float range
        hi = double(float(hi));
        lo = std::clamp(lo, double(brick.minValue), double(brick.maxValue));
        hi = std::clamp(hi, double(brick.minValue), double(brick.maxValue));
        const BrickRange decoded = decodeSubBlockRange(encodeSubBlockRange(lo, hi, brick), brick);
        ASSERT_LE(double(decoded.minValue), lo) << trial;
        ASSERT_GE(double(decoded.maxValue), hi) << trial;
        // Coarse by at most about two of the 255 steps.
        const double step = (double(brick.maxValue) - brick.minValue) / 255.0;
        ASSERT_LE(double(decoded.maxValue) - decoded.minValue, hi - lo + 2.5 * step + 1e-6 * scale)
            << trial;
    }
}

TEST(SubBlocks, EmptyAndConstantCodesHoldNoIsovalue) {
    const BrickRange brick{100.0f, 200.0f};
    const BrickRange empty = decodeSubBlockRange(SubBlockCode{}, brick);
    for (double iso : {99.5, 100.0, 150.5, 199.5, 200.0})
        EXPECT_FALSE(rangeHoldsIso(empty.minValue, empty.maxValue, iso)) << iso;
    const BrickRange constant{7.0f, 7.0f};
    const BrickRange c = decodeSubBlockRange(encodeSubBlockRange(7.0, 7.0, constant), constant);
    EXPECT_EQ(c.minValue, 7.0f);
    EXPECT_EQ(c.maxValue, 7.0f);
}

// The store's codes against each sub-block's cells measured directly in the volume.
TEST(SubBlocks, StoreCodesContainEachSubBlocksCells) {
    SynthParams p;
    p.kind = SynthKind::Head;
    p.dims = {70, 66, 37};  // partial bricks, and sub-blocks without cells, on every axis
    test::ScratchDir dir;
    StoreWriteOptions o;
    o.brickSize = 12;  // sub-blocks of 3 cells
    writeBrickStore(*openSynthVolume(p), dir.file("h.vdiso"), o);
    const BrickStoreReader store(dir.file("h.vdiso"));
    const auto memory = test::synthBrickSource(p, 12);
    const uint16_t* s = reinterpret_cast<const uint16_t*>(memory->samples().data());
    const BrickLayout& layout = store.layout();
    ASSERT_EQ(store.subBlockCodes().size(), store.index().size() * kSubBlocksPerBrick);  // every level's
    const int C = subBlockCells(layout.brickSize);
    int64_t withCells = 0, without = 0;
    for (int64_t id = 0; id < layout.brickCount(); ++id) {
        const Dims3 c = layout.brickCoord(id);
        const BrickRange whole{store.index()[size_t(id)].minValue, store.index()[size_t(id)].maxValue};
        for (int sb = 0; sb < kSubBlocksPerBrick; ++sb) {
            const int block[3] = {sb % 4, sb / 4 % 4, sb / 16};
            int64_t lo[3], hi[3];
            bool hasCells = true;
            for (int k = 0; k < 3; ++k) {
                lo[k] = c[k] * layout.brickSize + block[k] * C;
                hi[k] = std::min(lo[k] + C, c[k] * layout.brickSize + layout.cellsOnAxis(k, c[k]));
                hasCells = hasCells && lo[k] < hi[k];
            }
            const SubBlockCode code = store.subBlockCodes()[size_t(id) * kSubBlocksPerBrick + size_t(sb)];
            EXPECT_EQ(code.lo, memory->subBlockCodesOf(id)[size_t(sb)].lo);
            if (!hasCells) {
                EXPECT_EQ(code.lo, 255);
                EXPECT_EQ(code.hi, 0);
                ++without;
                continue;
            }
            ++withCells;
            uint16_t vmin = UINT16_MAX, vmax = 0;
            for (int64_t z = lo[2]; z <= hi[2]; ++z)
                for (int64_t y = lo[1]; y <= hi[1]; ++y)
                    for (int64_t x = lo[0]; x <= hi[0]; ++x) {
                        const uint16_t v = s[x + p.dims[0] * (y + p.dims[1] * z)];
                        vmin = std::min(vmin, v);
                        vmax = std::max(vmax, v);
                    }
            const BrickRange r = decodeSubBlockRange(code, whole);
            ASSERT_LE(r.minValue, float(vmin)) << id << " " << sb;
            ASSERT_GE(r.maxValue, float(vmax)) << id << " " << sb;
        }
    }
    EXPECT_GT(withCells, 0);
    EXPECT_GT(without, 0);
}

// The writer measures bricks where they lie in its slices (io/store/brick_measure.h): every
// level's ranges and codes are those of the gathered brick measured directly (its cells'
// corners, NaN as -inf; measureSubBlocks), for every sample type, NaN and infinities among
// f32's, brick sizes whose sub-blocks end early and volumes whose bricks end early.
TEST(SubBlocks, MeasuredInPlaceAsTheGatheredBrick) {
    const float nan = std::numeric_limits<float>::quiet_NaN(), inf = std::numeric_limits<float>::infinity();
    for (const ScalarType type : {ScalarType::U8, ScalarType::U16, ScalarType::I16, ScalarType::F32})
        for (const int brickSize : {7, 12}) {
            const Dims3 dims{41, 30, 27};
            test::MemoryVolume volume(dims, type);
            if (type == ScalarType::F32) {
                auto* f = reinterpret_cast<float*>(volume.bytes().data());
                for (size_t i = 0; i < volume.bytes().size() / 4; i += 97) f[i] = i % 3 == 0 ? nan : i % 3 == 1 ? inf : -inf;
                f[0] = nan;
            }
            test::ScratchDir dir;
            StoreWriteOptions o;
            o.brickSize = brickSize;
            writeBrickStore(volume, dir.file("m.vdiso"), o);
            const BrickStoreReader store(dir.file("m.vdiso"));
            ASSERT_GT(store.levels().size(), 1u);
            std::vector<unsigned char> brick(store.brickBytes());
            const size_t sampleBytes = scalarSize(type);
            const std::string what = std::string(scalarTypeName(type)) + " B " + std::to_string(brickSize);
            for (const BrickLevel& level : store.levels())
                for (int64_t i = 0; i < level.layout.brickCount(); ++i) {
                    const int64_t id = level.firstBrick + i;
                    const Dims3 coord = level.layout.brickCoord(i);
                    store.readBrick(id, brick.data());
                    const int side = level.layout.side();
                    double lo = std::numeric_limits<double>::infinity(), hi = -lo;
                    for (int z = 0; z <= level.layout.cellsOnAxis(2, coord[2]); ++z)
                        for (int y = 0; y <= level.layout.cellsOnAxis(1, coord[1]); ++y)
                            for (int x = 0; x <= level.layout.cellsOnAxis(0, coord[0]); ++x) {
                                const size_t at = BrickLayout::cornerIndex(side, x, y, z) * sampleBytes;
                                double v = 0;
                                visitScalarType(type, [&](auto zero) {
                                    decltype(zero) s;
                                    std::memcpy(&s, brick.data() + at, sizeof s);
                                    v = double(rangeValue(s));
                                });
                                lo = std::min(lo, v);
                                hi = std::max(hi, v);
                            }
                    const BrickEntry& e = store.index()[size_t(id)];
                    ASSERT_EQ(double(e.minValue), lo) << what << " brick " << id;
                    ASSERT_EQ(double(e.maxValue), hi) << what << " brick " << id;
                    SubBlockCode want[kSubBlocksPerBrick];
                    measureSubBlocks(type, brick.data(), level.layout, coord, {e.minValue, e.maxValue}, want);
                    for (int sb = 0; sb < kSubBlocksPerBrick; ++sb) {
                        const SubBlockCode got = store.subBlockCodes()[size_t(id) * kSubBlocksPerBrick + size_t(sb)];
                        ASSERT_TRUE(got.lo == want[sb].lo && got.hi == want[sb].hi) << what << " brick " << id << " sub-block " << sb;
                    }
                }
        }
}

TEST(SubBlocks, FormatOneStoresAreRefusedWithAReason) {
    test::ScratchDir dir;
    SynthParams p;
    p.dims = {20, 20, 20};
    writeBrickStore(*openSynthVolume(p), dir.file("new.vdiso"), {});
    std::vector<unsigned char> bytes = test::readFile(dir.file("new.vdiso"));
    const uint32_t one = 1;
    std::memcpy(bytes.data() + 8, &one, 4);
    test::writeFile(dir.file("old.vdiso"), bytes.data(), bytes.size());
    try {
        BrickStoreReader store(dir.file("old.vdiso"));
        FAIL() << "a format-1 store was opened";
    } catch (const IoError& e) {
        const std::string msg = e.what();
        EXPECT_NE(msg.find("old.vdiso"), std::string::npos) << msg;
        EXPECT_NE(msg.find("version 1"), std::string::npos) << msg;
        EXPECT_NE(msg.find("convert the volume again"), std::string::npos) << msg;
    }
}

// The same source with its sub-block ranges hidden.
class WithoutSubBlocks final : public BrickSource {
public:
    explicit WithoutSubBlocks(BrickSource& inner) : mInner(inner) {}
    const VolumeInfo& volume() const override { return mInner.volume(); }
    const BrickLayout& layout() const override { return mInner.layout(); }
    std::span<const BrickRange> brickRanges() const override { return mInner.brickRanges(); }
    BrickHandle acquire(int64_t id) override { return mInner.acquire(id); }

protected:
    void release(int64_t) override {}  // handles go back to the inner source

private:
    BrickSource& mInner;
};

TEST(SubBlocks, ViewDependentExtractionReadsFewerBricksForTheSameSurface) {
    SynthParams p;
    p.kind = SynthKind::Head;
    p.dims = {128, 128, 128};
    auto head = test::synthBrickSource(p, 16);
    WithoutSubBlocks plain(*head);
    const VolumeInfo& v = head->volume();
    int64_t readWith = 0, readWithout = 0, culled = 0;
    for (ViewPreset preset : {ViewPreset::Distant, ViewPreset::Normal, ViewPreset::Closeup})
        for (double iso : {kHeadSkinIso, kHeadBoneIso}) {
            const Camera camera = presetCamera(preset, v.origin, v.worldMax(), 600, 600);
            TriangleMesh a, b;
            PointSet pa, pb;
            const ExtractStats with = extractViewDependent(*head, camera, ViewExtractOptions::sage(iso), a, pa);
            const ExtractStats without = extractViewDependent(plain, camera, ViewExtractOptions::sage(iso), b, pb);
            const std::string label = std::string(viewPresetName(preset)) + " " + std::to_string(iso);
            // A brick none of whose sub-blocks passes has no meta-cell that would.
            EXPECT_EQ(a.positions, b.positions) << label;
            EXPECT_EQ(a.indices, b.indices) << label;
            EXPECT_EQ(pa.positions, pb.positions) << label;
            EXPECT_EQ(with.bricksActive + with.view.bricksCulledBySubBlocks, without.bricksActive) << label;
            EXPECT_EQ(without.view.bricksCulledBySubBlocks, 0) << label;
            readWith += with.bricksActive;
            readWithout += without.bricksActive;
            culled += with.view.bricksCulledBySubBlocks;
        }
    EXPECT_GT(culled, 0);
    EXPECT_LT(readWith, readWithout);
}

}  // namespace
}  // namespace vdiso
