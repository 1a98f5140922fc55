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
    bool readsTogether(int64_t a, int64_t b) const override {
        return mBase.readsTogether(mLevel.firstBrick + a, mLevel.firstBrick + b);
    }
    std::vector<BrickHandle> acquireTogether(std::span<const int64_t> ids) override {
        return mBase.acquireTogether(baseBricks(ids));
    }
    bool loadsInBackground() const override { return mBase.loadsInBackground(); }
    std::unique_ptr<BrickLoad> startAcquire(std::span<const int64_t> ids, std::function<void()> arrived,
                                            const std::atomic<bool>* cancel) override {
        return mBase.startAcquire(baseBricks(ids), std::move(arrived), cancel);
    }
    std::vector<BrickHandle> finishAcquire(BrickLoad& load) override { return mBase.finishAcquire(load); }
    size_t loadsWanted() const override { return mBase.loadsWanted(); }
    size_t loadsInFlight() const override { return mBase.loadsInFlight(); }
    int64_t brickCapacity() const override { return mBase.brickCapacity(); }

    // The underlying source's number of this level's brick `id`, and of several.
    int64_t baseBrick(int64_t id) const { return mLevel.firstBrick + id; }
    std::vector<int64_t> baseBricks(std::span<const int64_t> ids) const {
        std::vector<int64_t> base(ids.begin(), ids.end());
        for (int64_t& id : base) id += mLevel.firstBrick;
        return base;
    }

protected:
    void release(int64_t) override {}  // handles are the base's

private:
    BrickSource& mBase;
    BrickLevel mLevel;
    std::span<const BrickRange> mRanges;
};

}  // namespace vdiso
