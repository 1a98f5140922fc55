// Test support for extraction: a BrickSource over samples held in memory, analytic volumes,
// and mesh checks (closedness, canonical triangle sets).
#pragma once

#include <array>
#include <atomic>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "core/brick_source.h"
#include "core/synth/synth.h"
#include "core/trees/sub_blocks.h"
#include "core/mesh.h"

namespace vdiso::test {

// A volume of `type` whose sample at (x,y,z) is f(x,y,z) (converted to the type), served as
// bricks of `brickSize` cells, gathered on acquire like the store writer does.
class MemoryBrickSource final : public BrickSource {
public:
    MemoryBrickSource(const Dims3& dims, ScalarType type, int brickSize,
                      const std::function<double(int64_t, int64_t, int64_t)>& f);
    const VolumeInfo& volume() const override { return mInfo; }
    const BrickLayout& layout() const override { return mLayout; }
    std::span<const BrickRange> brickRanges() const override { return mRanges; }
    std::span<const SubBlockCode> subBlockCodesOf(int64_t id) const override {
        return std::span<const SubBlockCode>(mSubBlocks).subspan(size_t(id) * kSubBlocksPerBrick, kSubBlocksPerBrick);
    }
    BrickHandle acquire(int64_t id) override;
    const std::vector<unsigned char>& samples() const { return mSamples; }
    // Brick `id`'s own copy of its samples, to make bricks disagree on the ones they share.
    unsigned char* brickSamples(int64_t id) { return mBricks.at(size_t(id)).data(); }
    int64_t acquired() const { return mAcquired; }
    int pinned() const { return mPinned; }

protected:
    void release(int64_t) override { --mPinned; }

private:
    VolumeInfo mInfo;
    BrickLayout mLayout;
    std::vector<unsigned char> mSamples;
    std::vector<std::vector<unsigned char>> mBricks;
    std::vector<BrickRange> mRanges;
    std::vector<SubBlockCode> mSubBlocks;
    std::atomic<int64_t> mAcquired{0};  // acquire may be called from several threads
    std::atomic<int> mPinned{0};
};

// A generated volume (core/synth/synth.h) served from memory in bricks of `brickSize` cells.
std::unique_ptr<MemoryBrickSource> synthBrickSource(const SynthParams& params, int brickSize);

// Distance from the centre of a dims^3 grid, for spheres: the isosurface r is a sphere.
double sphereDistance(const Dims3& dims, int64_t x, int64_t y, int64_t z);

// "" if every undirected edge of the mesh is used by exactly two triangles, in opposite
// directions (a closed, consistently oriented surface); else what is wrong. With a volume,
// an edge used once is allowed where the surface leaves the volume: both its ends on the
// same face of the volume's box.
std::string checkClosedOriented(const TriangleMesh& mesh, const VolumeInfo* volume = nullptr);

// Triangles as sorted tuples of rounded positions, with rotation-normalised vertex order, so
// two meshes with the same triangles compare equal whatever their vertex numbering.
std::vector<std::array<float, 9>> canonicalTriangles(const TriangleMesh& mesh);

double enclosedVolume(const TriangleMesh& mesh);

}  // namespace vdiso::test
