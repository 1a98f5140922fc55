// The levels of detail one view-dependent extraction draws from (docs/design.md, "Trees over the bricks"; core/lod/view_levels.h).
//
// Per level: the source seen at that level (core/lod/level_source.h) and a culler over its grid
// (tests 1-3 against the one occlusion pyramid: culling works unchanged across levels). Per
// tree node that passed tests 1-3: the level it is extracted at, the coarsest level l >= 1 the
// node is one brick of whose cells span at most `lodError` pixels on screen, measured where
// the node is nearest the eye (2^l times the largest spacing, over the least view depth of its
// corners, in pixels of the image's focal length): 0 when there is none, and the node then
// descends to its children, or is a leaf extracted at level 0. A level whose brick holds no
// surface where the node's finer levels do is not taken either: a part thinner than its cells
// (core/lod/thin_parts.h) is gone from the whole brick, so the node descends. The traversal
// and its look-ahead ask the same object, so they agree on every brick.
#pragma once

#include <cstdint>
#include <memory>
#include <vector>

#include <glm/vec3.hpp>

#include "core/camera.h"
#include "core/lod/level_source.h"
#include "core/trees/minmax_tree.h"
#include "core/view/occlusion_pyramid.h"
#include "core/view/view_culler.h"

namespace vdiso {

class ViewLevels {
public:
    // lodError <= 0, or a tree over level 0 alone: level 0 only.
    ViewLevels(BrickSource& source, const MinMaxTree& tree, const Camera& camera,
               const OcclusionPyramid& pyramid, double iso, bool estimateBox, double lodError);

    int count() const { return int(mLevels.size()); }
    LevelSource& source(int level) { return mLevels[size_t(level)]->source; }
    const ViewCuller& culler(int level) const { return mLevels[size_t(level)]->culler; }

    // The level node (whose world box is [a, b]) is extracted at; 0: at level 0 or below.
    int levelOf(const MinMaxNode& node, const glm::dvec3& a, const glm::dvec3& b) const;
    // The most pixels a cell of `level` spans anywhere in the volume, as levelOf measures a
    // node's: the level's largest cell side over the least view depth of the volume's corners
    // (infinite when one is at or behind the eye).
    double largestCellPixels(int level) const;

    struct Brick {
        int level;
        int64_t id;     // in the source's numbering, through all levels
        int64_t local;  // in the level's own
    };
    // A leaf (level 0) or a node at levelOf(node) > 0 as a brick.
    Brick brickOf(const MinMaxNode& node, int level) const {
        const int64_t id = level == 0 ? mTree.brickOf(node) : mTree.brickOf(node, level);
        return {level, id, id - mLevels[size_t(level)]->source.baseBrick(0)};
    }
    // Extraction confined to `region` of level-0 bricks (nullptr: the whole volume; kept by
    // pointer). Full resolution only: with lodError > 0 a coarse brick would reach across it.
    void confineTo(const BrickRegion* region);
    // Whether `node` lies wholly outside the region (never, without one).
    bool outsideRegion(const MinMaxNode& node) const { return mRegion && !mRegion->meets(node.lo, node.hi); }

    // Test 1-3 for the brick's sub-blocks (ViewCuller::subBlocksShow).
    bool shows(const Brick& brick) const { return culler(brick.level).subBlocksShow(brick.local); }

    // The level level-0 brick c is extracted at, whether or not it shows: that of the first
    // node on the tree's path down to it that resolves (levelOf > 0, or the leaf); -1 when a
    // node on the way holds no surface at any level. Depends on the camera, not the pyramid.
    int levelAt(const int64_t c[3]) const;
    // The node on that path that resolves, and its brick: where the traversal extracts level-0
    // brick c (whether or not it shows); false when a node on the way holds no surface.
    bool resolve(const int64_t c[3], uint32_t& node, Brick& at) const;
    // The faces of `node`, extracted at `level`, that meet a region extracted at another level
    // (one that holds surface): bit 2a for its low face on axis a, 2a + 1 for its high face.
    // Those are the faces to cap (core/lod/face_cap.h). 0 with one level.
    unsigned seamFaces(const MinMaxNode& node, int level) const;

private:
    // The least view depth of the corners of the world box [a, b].
    double leastDepth(const glm::dvec3& a, const glm::dvec3& b) const;
    // Whether level l's brick at node holds the isovalue.
    bool holdsIso(const MinMaxNode& node, int l) const;
    // The faces of `node` inside the volume (those with a neighbour), in seamFaces' bits.
    unsigned innerFaces(const MinMaxNode& node) const;

    struct Level {
        LevelSource source;
        ViewCuller culler;
        double cellSize;  // world size of the level's largest cell side
        Level(BrickSource& base, int l, const Camera& camera, const OcclusionPyramid& pyramid, double iso,
              bool estimateBox);
    };
    const MinMaxTree& mTree;
    double mIso;
    std::vector<std::unique_ptr<Level>> mLevels;
    double mLodError;
    const BrickRegion* mRegion = nullptr;
    glm::dvec3 mEye, mForward;
    double mFocalPixels;  // pixels per unit of lateral size at unit depth
};

}  // namespace vdiso
