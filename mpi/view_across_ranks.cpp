#include "mpi/view_across_ranks.h"

#include <chrono>
#include <climits>
#include <cstring>
#include <optional>
#include <stdexcept>
#include <type_traits>

#include "core/clock.h"
#include "cache/cache_plan.h"
#include "core/extract/depth_slabs.h"
#include "core/extract/image_strips.h"
#include "mpi/rank_status.h"

namespace vdiso::mpi {

namespace {


// Thrown from a coverage round when another rank has failed: it ends this rank's traversal
// without being a failure of its own (the failing rank is the one named).
struct OtherRankFailed {};

// The coverage rounds of the object-space partition (see the header). Rank r holds slab r.
class CoverageRounds final : public CoverageExchange {
public:
    CoverageRounds(const Communicator& world, const Communicator& reversed, int eyeSlab, size_t tiles, int every)
        : mWorld(world), mReversed(reversed), mEyeSlab(eyeSlab), mEvery(every), mFinal(tiles, 0) {}

    void between(OcclusionPyramid& pyramid, int64_t bricks) override {
        if (bricks < mNext) return;
        mNext = bricks + mEvery;
        round(pyramid.tiles(), true, false, &pyramid);
        if (mFailed) throw OtherRankFailed{};
    }
    void ended(const OcclusionPyramid& pyramid) override { mFinal.assign(pyramid.tiles().begin(), pyramid.tiles().end()); }

    // This rank's traversal has ended (or failed, `failed`): rounds with its final coverage
    // until every rank's has ended.
    void finish(bool failed) {
        while (round(mFinal, false, failed, nullptr) > 0) {
        }
    }

    uint64_t rounds() const { return mRounds; }
    uint64_t maskBytes() const { return mMaskBytes; }

private:
    static constexpr uint64_t kFailedFlag = uint64_t(1) << 32;

    // One round: every rank says whether it still runs and whether it failed, and gives its
    // coverage to the scans; the coverage of the slabs in front is merged `into` the pyramid.
    // The slabs in front of slab s are DepthSlabs::inFront's: those from the eye's slab up to s
    // (the ascending scan, to which the slabs below the eye's give nothing) or down to s (the
    // descending scan on the reversed communicator). Returns how many ranks still run.
    uint64_t round(std::span<const uint64_t> tiles, bool running, bool failed, OcclusionPyramid* into) {
        const uint64_t state = mWorld.sum((running ? 1 : 0) + (failed ? kFailedFlag : 0));
        mFailed = mFailed || state >= kFailedFlag;
        const int slab = mWorld.rank(), last = mWorld.size() - 1;
        const std::vector<uint64_t> none(tiles.size(), 0);
        std::vector<uint64_t> front;
        // Slabs beyond the eye's, in increasing order: each gets the OR of those from the eye's
        // up to it. The slabs on the other side give nothing to this scan.
        if (mEyeSlab < last) {
            std::vector<uint64_t> up = mWorld.exclusiveOr(slab >= mEyeSlab ? tiles : std::span<const uint64_t>(none));
            if (slab > mEyeSlab) front = std::move(up);
            mMaskBytes += tiles.size() * sizeof(uint64_t);
        }
        if (mEyeSlab > 0) {
            std::vector<uint64_t> down = mReversed.exclusiveOr(slab <= mEyeSlab ? tiles : std::span<const uint64_t>(none));
            if (slab < mEyeSlab) front = std::move(down);
            mMaskBytes += tiles.size() * sizeof(uint64_t);
        }
        if (into && !front.empty() && into->coverTiles(front)) into->propagate();
        ++mRounds;
        return state % kFailedFlag;
    }

    const Communicator& mWorld;
    const Communicator& mReversed;
    int mEyeSlab;
    int64_t mEvery, mNext = 0;
    std::vector<uint64_t> mFinal;
    bool mFailed = false;
    uint64_t mRounds = 0, mMaskBytes = 0;
};

// A rank's triangles and points as bytes: counts, then positions, normals, indices, points.
std::vector<unsigned char> packed(const TriangleMesh& mesh, const PointSet& points) {
    const uint64_t counts[3] = {mesh.positions.size(), mesh.indices.size(), points.size()};
    std::vector<unsigned char> bytes(sizeof counts + (counts[0] * 2 + counts[2] * 2) * sizeof(glm::vec3) +
                                     counts[1] * sizeof(uint32_t));
    unsigned char* at = bytes.data();
    auto put = [&](const void* data, size_t n) {
        if (n) std::memcpy(at, data, n);
        at += n;
    };
    put(counts, sizeof counts);
    put(mesh.positions.data(), counts[0] * sizeof(glm::vec3));
    put(mesh.normals.data(), counts[0] * sizeof(glm::vec3));
    put(mesh.indices.data(), counts[1] * sizeof(uint32_t));
    put(points.positions.data(), counts[2] * sizeof(glm::vec3));
    put(points.normals.data(), counts[2] * sizeof(glm::vec3));
    return bytes;
}

// Appends every rank's packed output in `all` to mesh and points.
void appendPacked(std::span<const unsigned char> all, TriangleMesh& mesh, PointSet& points) {
    const unsigned char* at = all.data();
    const unsigned char* end = all.data() + all.size();
    auto take = [&](auto& out, uint64_t n) {
        using T = typename std::decay_t<decltype(out)>::value_type;
        const size_t bytes = size_t(n) * sizeof(T);
        if (size_t(end - at) < bytes) throw std::logic_error("view across ranks: a gathered part is cut short");
        const size_t first = out.size();
        out.resize(first + size_t(n));
        if (bytes) std::memcpy(out.data() + first, at, bytes);
        at += bytes;
    };
    while (at < end) {
        std::vector<uint64_t> counts;
        take(counts, 3);
        const uint32_t offset = mesh.nextVertex();
        const size_t firstIndex = mesh.indices.size();
        take(mesh.positions, counts[0]);
        take(mesh.normals, counts[0]);
        take(mesh.indices, counts[1]);
        for (size_t i = firstIndex; i < mesh.indices.size(); ++i) mesh.indices[i] += offset;
        take(points.positions, counts[2]);
        take(points.normals, counts[2]);
    }
}

}  // namespace

RanksViewResult extractViewAcrossRanks(const Communicator& comm, BrickCache& cache, const Camera& camera,
                                       const RanksViewOptions& options) {
    const auto start = Clock::now();
    RanksViewResult result;
    result.ranks = comm.size();
    result.partition = options.partition;
    ViewExtractOptions view = options.view;
    RankViewFigures mine;

    // The parts: computed alike on every rank from the index and the camera.
    BrickRegion region;
    std::optional<Communicator> reversed;
    std::optional<CoverageRounds> rounds;
    if (options.partition == ViewPartition::Object) {
        if (view.lodError > 0 || view.threads != 1 || options.exchangeBricks < 1)
            throw std::invalid_argument("object-space partition: one thread per rank, lod error 0 and rounds of "
                                        "1 brick or more");
        const DepthSlabs slabs = depthSlabs(cache, camera, view.iso, comm.size());
        result.axis = slabs.axis;
        result.eyeSlab = slabs.eyeSlab;
        region = slabs.region(comm.rank(), cache.layout());
        mine.partBegin = int(slabs.cuts[size_t(comm.rank())]);
        mine.partEnd = int(slabs.cuts[size_t(comm.rank()) + 1]);
        reversed.emplace(comm.reversed());
        rounds.emplace(comm, *reversed, slabs.eyeSlab, OcclusionPyramid::tileCount(camera.width, camera.height),
                       options.exchangeBricks);
        view.region = &region;
        view.coverage = &*rounds;
    } else {
        if (comm.size() > camera.width)
            throw std::invalid_argument("image-space partition: more ranks than the image has columns");
        const std::vector<int> columns = stripColumns(cache, camera, view.iso, comm.size(), 0, camera.width);
        mine.partBegin = view.columnBegin = columns[size_t(comm.rank())];
        mine.partEnd = view.columnEnd = columns[size_t(comm.rank()) + 1];
    }

    // Extract this rank's part.
    TriangleMesh mesh;
    PointSet points;
    ExtractStats stats;
    const CacheCounters before = cache.counters();
    runPhase(comm, [&] {
        try {
            stats = extractViewDependent(cache, camera, view, mesh, points);
        } catch (const OtherRankFailed&) {
            // That rank is named; this one's output is dropped with the job.
        } catch (...) {
            if (rounds) rounds->finish(true);
            throw;
        }
        if (rounds) rounds->finish(false);
    });
    const CacheCounters io = cache.counters() - before;
    mine.bricksLoaded = io.misses;
    mine.bytesRead = io.bytesRead;
    mine.ioSeconds = io.readSeconds;
    mine.decodeSeconds = io.decodeSeconds;
    mine.triangles = mesh.triangleCount();
    mine.points = points.size();
    mine.bricksActive = stats.bricksActive;
    mine.culledByRegion = stats.view.culledByRegion;
    mine.culledByOcclusion = stats.view.culledByOcclusion;
    mine.seconds = std::chrono::duration<double>(Clock::now() - start).count();

    // Rank 0 gathers the surface, for the picture and the mesh file: each rank packs its part
    // and rank 0 makes room for all of them, each step agreed on, so that no rank can fail while
    // the others are inside the gather.
    if (options.gather) {
        std::vector<unsigned char> part, all;
        runPhase(comm, [&] { part = packed(mesh, points); });
        result.gatheredBytes = comm.sum(part.size());
        runPhase(comm, [&] {
            if (result.gatheredBytes > uint64_t(INT_MAX))
                throw std::runtime_error("the ranks' visible surface is " + std::to_string(result.gatheredBytes >> 20) +
                                         " MiB, more than rank 0 can gather at once (2 GiB)");
            if (comm.rank() == 0) all.resize(size_t(result.gatheredBytes));
        });
        comm.gatherBytes(part, 0, all);
        runPhase(comm, [&] {
            if (comm.rank() == 0) appendPacked(all, result.mesh, result.points);
        });
    }

    // Statistics: summed on every rank, each rank's on rank 0.
    const auto sum = [&](auto v) { return decltype(v)(comm.sum(uint64_t(v))); };
    ExtractStats& s = result.stats;
    s.triangles = sum(mine.triangles);
    s.vertices = sum(uint64_t(mesh.vertexCount()));
    s.nodesVisited = sum(stats.nodesVisited);
    s.bricksActive = sum(stats.bricksActive);
    s.metaCellsActive = sum(stats.metaCellsActive);
    s.cellsActive = sum(stats.cellsActive);
    ViewCounters& v = s.view;
    v.culledByRange = sum(stats.view.culledByRange);
    v.culledByFrustum = sum(stats.view.culledByFrustum);
    v.culledByOcclusion = sum(stats.view.culledByOcclusion);
    v.culledByRegion = sum(stats.view.culledByRegion);
    v.droppedSubPixel = sum(stats.view.droppedSubPixel);
    v.cellsCulled = sum(stats.view.cellsCulled);
    v.polygonsHidden = sum(stats.view.polygonsHidden);
    v.bricksCulledBySubBlocks = sum(stats.view.bricksCulledBySubBlocks);
    v.bricksPrefetchedUnused = sum(stats.view.bricksPrefetchedUnused);
    v.coarseBricks = sum(stats.view.coarseBricks);
    v.cappedFaces = sum(stats.view.cappedFaces);
    v.points = sum(uint64_t(points.size()));
    result.bricksLoaded = sum(io.misses);
    result.bytesRead = sum(io.bytesRead);
    if (rounds) {
        result.rounds = rounds->rounds();
        result.maskBytes = comm.max(rounds->maskBytes());
    }
    const auto u = [&](uint64_t x) { return comm.gather(x, 0); };
    const auto d = [&](double x) { return comm.gather(x, 0); };
    const auto begin = u(uint64_t(mine.partBegin)), end = u(uint64_t(mine.partEnd)), loaded = u(mine.bricksLoaded),
               bytes = u(mine.bytesRead), triangles = u(mine.triangles), pts = u(mine.points),
               active = u(uint64_t(mine.bricksActive)), region_ = u(uint64_t(mine.culledByRegion)),
               occlusion = u(uint64_t(mine.culledByOcclusion));
    const auto seconds = d(mine.seconds), ioSeconds = d(mine.ioSeconds), decodeSeconds = d(mine.decodeSeconds);
    for (size_t r = 0; r < begin.size(); ++r)
        result.perRank.push_back({int(begin[r]), int(end[r]), loaded[r], bytes[r], triangles[r], pts[r],
                                  int64_t(active[r]), int64_t(region_[r]), int64_t(occlusion[r]), seconds[r],
                                  ioSeconds[r], decodeSeconds[r]});
    result.seconds = std::chrono::duration<double>(Clock::now() - start).count();
    s.extractSeconds = result.seconds;
    return result;
}

}  // namespace vdiso::mpi
