// One level of detail of a brick source as a source of its own (core/brick_levels.h): its
// volume (the level's grid, cells 2^l larger), its layout, and its bricks' ranges and samples
// by the level's own brick numbers. Every extractor that takes a source works on a coarse
// level through it unchanged: `vdiso extract --level L`, and the view-dependent traversal's
// coarse bricks. Handles it gives out belong to the underlying source.
#pragma once

#include "core/brick_source.h"

namespace vdiso {

class LevelSource final : public BrickSource {
public:
    // `level` must be below base.levelCount().
    LevelSource(BrickSource& base, int level);

    const VolumeInfo& volume() const override { return mLevel.volume; }
    const BrickLayout& layout() const override { return mLevel.layout; }
    std::span<const BrickRange> brickRanges() const override { return mRanges; }
    std::span<const SubBlockCode> subBlockCodesOf(int64_t id) const override {
        return mBase.subBlockCodesOf(mLevel.firstBrick + id);
    }
    BrickHandle acquire(int64_t id) override { return mBase.acquire(mLevel.firstBrick + id); }
    bool isResident(int64_t id) const override { return mBase.isResident(mLevel.firstBrick + id); }
    int64_t brickCapacity() const override { return mBase.brickCapacity(); }

    // The underlying source's number of this level's brick `id`.
    int64_t baseBrick(int64_t id) const { return mLevel.firstBrick + id; }

protected:
    void release(int64_t) override {}  // handles are the base's

private:
    BrickSource& mBase;
    BrickLevel mLevel;
    std::span<const BrickRange> mRanges;
};

}  // namespace vdiso
