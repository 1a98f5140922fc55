// Extracting from one store, frame after frame: what vdiso extract and the Python module's
// Store.extract both run. The session holds the brick cache and what is kept across the frames
// of a path (the meta-cell ranges, the view-dependent methods' tree); extract() runs one frame
// from one camera and frameStats() describes it as the --stats JSON object.
#pragma once

#include <memory>
#include <optional>
#include <string>

#include "app/extract_settings.h"
#include "cache/brick_cache.h"
#include "core/camera.h"
#include "core/extract/extract_stats.h"
#include "core/mesh.h"
#include "core/lod/thin_parts.h"
#include "core/trees/meta_cell_range_cache.h"
#include "core/trees/minmax_tree.h"
#include "core/orientation.h"
#include "core/progress.h"
#include "io/store/brick_store.h"
#include "io/json.h"
#include "io/mesh/mesh_post.h"

namespace vdiso {

struct ExtractFrame {
    TriangleMesh mesh;  // volume space; empty when it went to a sink
    PointSet points;    // sage, wise: the sub-pixel points
    ExtractStats stats;
    CacheCounters io;  // this frame's reads, the cache kept across frames
    CachePlan plan;
    std::optional<MeshPostStats> post;
    bool streamed = false;  // the mesh went to the sink as it was extracted
};

// Where a frame's mesh goes besides ExtractFrame::mesh.
struct FrameOutput {
    // A full method (octree, noise) hands its mesh here as it is extracted and keeps none:
    // memory holds a bounded part of it. Null: the whole mesh is held.
    MeshSink* sink = nullptr;
    // Post-processing's side files go beside this path (io/mesh/mesh_post.h); needed when the
    // settings post-process.
    std::string postBeside;
    ProgressFn postProgress;
};

class ExtractSession {
public:
    // Checks the settings (SettingsError) and against the store (a level it does not hold); adapts
    // readers and look-ahead to a store at a URL (adaptToRemoteStore) or on this machine
    // (adaptToLocalStore: no more readers than the cores beside the extraction).
    ExtractSession(const BrickStoreReader& store, ExtractSettings settings);
    // Other settings for the frames to come, checked as the constructor checks them (a bad one
    // throws and changes nothing). The cache, its bricks, the meta-cell ranges and the tree are
    // kept unless the cache's budget changes: a second extraction of the same store reads no
    // brick the first left in the cache, whatever its isovalue or method.
    void reconfigure(ExtractSettings settings);

    // One frame; `camera` is needed by sage and wise, ignored by octree and noise.
    ExtractFrame extract(const std::optional<Camera>& camera, const FrameOutput& output = {},
                         const ProgressFn& progress = {});

    // Hands a frame's mesh and points back, for the next frame to fill emptied: the frames of a
    // path (vdiso extract --path) then write into pages the process holds already instead of
    // faulting fresh ones in every frame.
    void recycle(ExtractFrame&& frame);

    // The frame's statistics as vdiso extract --stats writes them (without the oracle's).
    // `meshWritten`: a mesh or points file was written (mesh_space is then stated).
    JsonObject frameStats(const ExtractFrame& frame, bool meshWritten) const;

    const ExtractSettings& settings() const { return mSettings; }
    const BrickStoreReader& store() const { return mStore; }
    BrickCache& cache() { return *mCache; }
    // Building the view-dependent tree, before the first frame (0 for the full methods, and when
    // the tree was already built for earlier settings).
    double treeSeconds() const { return mTreeSeconds; }
    // Meshes go from volume space to this: physical space unless the settings say volume.
    SpaceTransform meshTransform() const;

private:
    const BrickStoreReader& mStore;
    ExtractSettings mSettings;
    std::unique_ptr<BrickCache> mCache;
    std::unique_ptr<MetaCellRangeCache> mRanges;
    std::unique_ptr<LostPartMemo> mLostParts;  // as many bricks as the ranges
    std::optional<MinMaxTree> mTree;
    double mTreeSeconds = 0;
    TriangleMesh mSpareMesh;  // recycle()'s, for the next frame
    PointSet mSparePoints;
};

}  // namespace vdiso
