#include "core/clock.h"
#include "mpi/extract_across_ranks.h"

#include <chrono>
#include <optional>

#include "cache/brick_cache.h"
#include "core/extract/extract_full.h"
#include "core/lod/level_source.h"
#include "core/orientation.h"
#include "io/store/brick_store.h"
#include "io/mesh/mesh_writer.h"
#include "io/mesh/stl_writer.h"
#include "mpi/brick_partition.h"
#include "mpi/collective_mesh.h"
#include "mpi/rank_status.h"
#include "mpi/rank_weld.h"

namespace vdiso::mpi {

namespace {

}  // namespace

RanksExtractResult extractOctreeAcrossRanks(const Communicator& comm, const RanksExtractOptions& options) {
    const auto start = Clock::now();
    ExtractSettings s = options.settings;
    if (!s.iso) throw std::invalid_argument("extractOctreeAcrossRanks: no isovalue");
    const double iso = *s.iso;
    const bool ply = !options.meshPath.empty() && meshFormatFor(options.meshPath) == MeshFormat::Ply;
    const bool stl = !options.meshPath.empty() && meshFormatFor(options.meshPath) == MeshFormat::Stl;
    if (!options.meshPath.empty() && !ply && !stl)
        throw std::invalid_argument(options.meshPath + ": the octree method writes .ply and .stl meshes under MPI");
    std::optional<BrickStoreReader> store;
    std::optional<BrickCache> cache;
    std::optional<LevelSource> level;
    BrickPartition partition;
    TriangleMesh mesh;
    EdgeVertexMap border;
    ExtractStats stats;
    CacheCounters io;
    RankExtractFigures mine;

    // Open, partition and extract this rank's part.
    runPhase(comm, [&] {
        store.emplace(options.store, StoreOpenOptions{options.cold ? ReadMode::Cold : ReadMode::Buffered, options.remote});
        if (store->readsRemotely()) adaptToRemoteStore(s);  // read-ahead as vdiso extract's session sets it
        cache.emplace(*store, uint64_t(s.cacheMb) << 20);
        level.emplace(*cache, 0);
        const CachePlan plan = planCache(s, *cache, s.threads);
        std::vector<int64_t> active = octreeActiveBricks(*level, iso, &stats.nodesVisited);
        std::vector<uint64_t> weights = activeSubBlockWeights(*cache, active, iso);
        partition = partitionBricks(std::move(active), std::move(weights), comm.size(), level->layout().brickCount());
        const std::span<const int64_t> part = partition.part(comm.rank());
        mine.bricks = part.size();
        mine.weight = partition.weightOf(comm.rank());
        if (!part.empty()) {
            mine.firstBrick = part.front();
            mine.lastBrick = part.back();
            FullExtractOptions extract{iso, s.metaCellSize, plan.threads};
            extract.prefetchBricks = plan.prefetchBricks;
            extract.bricks = part;
            extract.borderVertices = &border;
            const int64_t nodes = stats.nodesVisited;
            stats = extractOctree(*level, extract, mesh);
            stats.nodesVisited = nodes;
        }
        io = cache->counters();
    });
    mine.extractSeconds = secondsSince(start);

    // Map to the output space (as vdiso extract does, piece by piece; skipped when it is the
    // identity, as MeshFileWriter skips it: 0 + -0 is +0, so bytes would differ). STL shares no
    // vertex: its triangles go out as each rank made them. Welding across ranks gives PLY's
    // one numbering (and everyone's vertex counts).
    runPhase(comm, [&] {
        const SpaceTransform transform = volumeToPhysical(store->volume());
        if (s.physicalMeshes.value_or(true) && !transform.isIdentity()) transformMesh(transform, mesh);
    });
    if (stl) writeStlCollectively(comm, options.meshPath, options.overwrite, mesh);
    RankMeshNumbering numbering;
    runPhase(comm, [&] {
        numbering = weldAcrossRanks(comm, partition, level->volume(), level->layout(), border, mesh);
    });
    if (ply) writePlyCollectively(comm, options.meshPath, options.overwrite, mesh, numbering);

    mine.bricksLoaded = io.misses;
    mine.bytesRead = io.bytesRead;
    mine.ioSeconds = io.readSeconds;
    mine.decodeSeconds = io.decodeSeconds;
    mine.triangles = numbering.triangles;
    mine.verticesOwned = numbering.ownedVertices;
    mine.verticesBorrowed = numbering.borrowedVertices;
    mine.weldBytesSent = numbering.bytesSent;
    if (ply)
        mine.meshBytes = numbering.ownedVertices * kPlyVertexBytes + numbering.triangles * kPlyFaceBytes;
    else if (stl)
        mine.meshBytes = numbering.triangles * kStlTriangleBytes;
    mine.seconds = secondsSince(start);

    RanksExtractResult result;
    result.ranks = comm.size();
    result.stats.triangles = numbering.totalTriangles;
    result.stats.vertices = numbering.totalVertices;
    result.stats.bricksActive = int64_t(partition.bricks.size());
    result.stats.nodesVisited = stats.nodesVisited;
    result.stats.metaCellsActive = int64_t(comm.sum(uint64_t(stats.metaCellsActive)));
    result.stats.cellsActive = int64_t(comm.sum(uint64_t(stats.cellsActive)));
    result.bricksLoaded = comm.sum(io.misses);
    result.bytesRead = comm.sum(io.bytesRead);
    result.readMethod = store->readMethod();
    result.source = frameSourceOf(*store);
    // Rank 0 collects every rank's figures.
    const auto u = [&](uint64_t v) { return comm.gather(v, 0); };
    const auto d = [&](double v) { return comm.gather(v, 0); };
    const auto bricks = u(mine.bricks), first = u(uint64_t(mine.firstBrick)), last = u(uint64_t(mine.lastBrick)),
               weight = u(mine.weight), loaded = u(mine.bricksLoaded), bytes = u(mine.bytesRead),
               triangles = u(mine.triangles), owned = u(mine.verticesOwned), borrowed = u(mine.verticesBorrowed),
               weld = u(mine.weldBytesSent), meshBytes = u(mine.meshBytes);
    const auto seconds = d(mine.seconds), extractSeconds = d(mine.extractSeconds), ioSeconds = d(mine.ioSeconds),
               decodeSeconds = d(mine.decodeSeconds);
    for (size_t r = 0; r < bricks.size(); ++r)
        result.perRank.push_back({bricks[r], int64_t(first[r]), int64_t(last[r]), weight[r], loaded[r], bytes[r],
                                  triangles[r], owned[r], borrowed[r], weld[r], meshBytes[r], seconds[r],
                                  extractSeconds[r], ioSeconds[r], decodeSeconds[r]});
    result.seconds = secondsSince(start);
    return result;
}

}  // namespace vdiso::mpi
