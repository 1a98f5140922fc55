#include "app/extract_session.h"

#include <algorithm>
#include <memory>
#include <utility>

#include "cache/cache_plan.h"
#include "core/clock.h"
#include "core/extract/extract_full.h"
#include "core/extract/extract_view.h"
#include "core/lod/level_source.h"
#include "core/orientation.h"
#include "io/store/external_bricks.h"
#include "app/extract_stats_json.h"
#include "io/process_stats.h"
#include "io/remote/remote_file.h"

namespace vdiso {

namespace {

void checked(const ExtractSettings& s, const BrickStoreReader& store) {
    checkExtractSettings(s);
    const int levels = store.header().levelCount;
    if (s.level >= levels)
        throw SettingsError("level", std::to_string(s.level) + ": " + store.path() + " holds " +
                                         std::to_string(levels) + " level" + (levels == 1 ? "" : "s") +
                                         " of detail (0 to " + std::to_string(levels - 1) + ")");
}

}  // namespace

ExtractSession::ExtractSession(const BrickStoreReader& store, ExtractSettings settings) : mStore(store) {
    reconfigure(std::move(settings));
}

void ExtractSession::reconfigure(ExtractSettings settings) {
    checked(settings, mStore);  // before anything changes: a bad setting leaves the session as it was
    if (store().readsRemotely())
        adaptToRemoteStore(settings);
    else
        adaptToLocalStore(settings, machineThreads());
    // Another budget is another cache (and what is kept beside it); the same keeps its bricks.
    if (!mCache || settings.cacheMb != mSettings.cacheMb) {
        auto cache = std::make_unique<BrickCache>(mStore, settings.cacheMb << 20);  // may throw: nothing changed
        // Meta-cell ranges are kept across the frames of a path, for as many bricks as the cache.
        const size_t keptBricks = cache->budgetBytes() / mStore.brickBytes();
        auto ranges = std::make_unique<MetaCellRangeCache>(keptBricks);
        auto lostParts = std::make_unique<LostPartMemo>(keptBricks);
        mTree.reset();  // built over the old cache's levels
        mCache = std::move(cache);
        mRanges = std::move(ranges);
        mLostParts = std::move(lostParts);
    }
    mSettings = std::move(settings);
    mTreeSeconds = 0;
    if (isViewDependent(mSettings.method) && !mTree) {
        const auto start = Clock::now();
        mTree.emplace(mCache->levels(), mCache->brickRanges(), mSettings.threads > 0 ? mSettings.threads : machineThreads());
        mTreeSeconds = secondsSince(start);
    }
}

SpaceTransform ExtractSession::meshTransform() const {
    return mSettings.physicalMeshes.value_or(true) ? volumeToPhysical(mStore.volume()) : SpaceTransform{};
}

ExtractFrame ExtractSession::extract(const std::optional<Camera>& camera, const FrameOutput& output,
                                     const ProgressFn& progress) {
    const ExtractSettings& s = mSettings;
    const CacheCounters before = mCache->counters();
    ExtractFrame f;
    f.mesh = std::exchange(mSpareMesh, TriangleMesh{});
    f.points = std::exchange(mSparePoints, PointSet{});
    f.plan = planCache(s, *mCache, machineThreads());
    if (isViewDependent(s.method)) {
        if (!camera) throw SettingsError("camera", "is needed by the view-dependent methods, sage and wise");
        ViewExtractOptions v = viewExtractOptions(s, f.plan);
        v.rangeCache = &*mRanges;
        v.lostParts = &*mLostParts;
        v.tree = &*mTree;
        f.stats = extractViewDependent(*mCache, *camera, v, f.mesh, f.points, progress);
    } else {
        FullExtractOptions extract{*s.iso, s.metaCellSize, f.plan.threads};
        extract.prefetchBricks = f.plan.prefetchBricks;
        extract.prefetchReaders = s.readers;
        LevelSource level(*mCache, s.level);
        // Post-processing takes the surface brick by brick and hands its result on to the sink
        // or to the mesh held.
        MeshAppender held(f.mesh);
        std::optional<PostProcessedMesh> postProcess;
        if (s.post.any()) {
            MeshPostOptions shape = s.post;
            shape.threads = f.plan.threads;
            postProcess.emplace(output.postBeside, level.layout(), shape,
                                output.sink ? *output.sink : static_cast<MeshSink&>(held));
            extract.brickSink = &*postProcess;
        } else if (output.sink) {
            extract.sink = output.sink;
        }
        f.streamed = output.sink != nullptr;
        // Brick by brick, the extraction's own mesh is a passing buffer, not the one held.
        TriangleMesh passing;
        TriangleMesh& into = postProcess ? passing : f.mesh;
        f.stats = s.method == "noise" ? extractNoise(level, extract, into, progress)
                                      : extractOctree(level, extract, into, progress);
        if (postProcess) {
            f.post = postProcess->finish(output.postProgress);
            f.stats.triangles = f.post->trianglesOut;
            f.stats.vertices = f.post->verticesOut;
        }
    }
    f.io = mCache->counters() - before;
    return f;
}

void ExtractSession::recycle(ExtractFrame&& frame) {
    mSpareMesh = std::move(frame.mesh);
    mSpareMesh.clear();
    mSpareMesh.firstVertex = 0;
    mSparePoints = std::move(frame.points);
    mSparePoints.clear();
}

JsonObject ExtractSession::frameStats(const ExtractFrame& f, bool meshWritten) const {
    const ExtractSettings& o = mSettings;
    const ExtractStats& stats = f.stats;
    const CacheCounters& io = f.io;
    const BrickStoreReader& store = mStore;
    const VolumeInfo& volume = store.volume();
    JsonObject s;
    addFrameHeader(s, o, frameSourceOf(store), f.plan.threads, stats, uint64_t(f.points.size()), meshWritten);
    s.add("mesh_streamed", f.streamed);
    if (const auto& post = f.post) {
        s.add("smooth", o.post.smoothIterations).add("decimate", o.post.decimateRatio);
        s.add("largest", o.post.largestPiece).add("min_piece", o.post.minPieceTriangles);
        s.add("triangles_extracted", post->trianglesIn).add("vertices_extracted", post->verticesIn);
        s.add("pieces", post->pieces).add("pieces_kept", post->piecesKept);
        s.add("largest_piece_triangles", post->largestPieceTriangles);
        s.add("post_slabs", post->slabs).add("post_halo_slabs", post->haloSlabs);
        s.add("post_window_triangles_max", post->largestWindowTriangles);
        s.add("post_spool_mb", double(post->spoolBytes) / 1e6);
        s.add("pieces_s", post->piecesSeconds).add("post_s", post->finishSeconds);
    }
    s.add("extract_s", stats.extractSeconds).add("preprocess_s", stats.preprocessSeconds);
    s.add("io_s", io.readSeconds).add("decode_s", io.decodeSeconds);
    s.add("read_method", store.readMethod());
    // Everything read from the store's file, or fetched over the network, since the open: the
    // index's parts as well as the bricks (ByteSource::bytesRead). What a local run and a
    // remote one compare by.
    s.add("store_bytes", store.sourceBytesRead());
    // A remote store: every request sent (the open's, the index's, retries) and the bytes they
    // brought, from the open on.
    if (const RemoteFile* remote = store.remote()) {
        s.add("remote_requests", remote->requests()).add("remote_bytes", remote->bytesFetched());
        s.add("remote_stragglers", remote->stragglers());
        // What the link held at the end, in requests (RemoteFile::wantedInFlight, unbounded).
        s.add("remote_in_flight_wanted", remote->wantedInFlight(1, 1 << 20));
        s.add("disk_cache_hits", remote->diskCacheHits()).add("disk_cache_bytes", remote->diskCacheBytes());
    }
    // An index: the indexed array's chunks read, as stored, and its requests when remote.
    if (const ExternalBricks* external = store.external()) {
        s.add("chunks_read", external->chunksRead()).add("chunk_bytes_read", external->chunkBytesRead());
        s.add("chunk_requests", external->requests());
    }
    s.add("prefetch", f.plan.threads > 1 && !isViewDependent(o.method) ? 0 : f.plan.prefetchBricks);
    s.add("readers", o.readers);
    // I/O the extraction did not wait for: read and decode time spent ahead of it (summed over
    // the reader threads, as io_s and decode_s are). With image strips a lower bound: a strip
    // waiting for a brick another strip loads counts as waiting, the read only once.
    s.add("brick_wait_s", stats.brickWaitSeconds);
    s.add("io_hidden_s", std::max(0.0, io.readSeconds + io.decodeSeconds - stats.brickWaitSeconds));
    s.add("bricks_loaded", io.misses).add("bricks_requested", io.requests).add("bytes_read", io.bytesRead);
    addTraversalCounters(s, o.method, stats);
    s.add("voxels_per_s", double(volume.sampleCount()) / stats.extractSeconds);
    return s;
}

}  // namespace vdiso
