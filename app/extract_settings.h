// The settings of one extraction, as every front end (vdiso, vdiso-mpi, the Python module)
// fills them, with the checks they share and what they derive: the cache plan and the
// view-dependent options. Messages name quantities, not flags: a SettingsError
// (core/settings_error.h) carries the setting it is about, and each front end puts its own
// spelling of it in front ("--lod-error", "lod_error=").
#pragma once

#include <cstdint>
#include <optional>
#include <stdexcept>
#include <string>

#include "cache/brick_cache.h"
#include "cache/cache_plan.h"
#include "core/extract/brick_prefetcher.h"
#include "core/extract/extract_view.h"
#include "core/settings_error.h"
#include "core/mesh_post/mesh_slabs.h"

namespace vdiso {

// The picture a view is made for when no size is given (vdiso extract --size, Python's size).
constexpr int kDefaultImageWidth = 800, kDefaultImageHeight = 800;

struct ExtractSettings {
    std::string method = "octree";  // octree, noise (full); sage, wise (view-dependent)
    std::optional<double> iso;
    double lodError = 1.0;  // sage, wise: pixels of error a coarser level may make
    bool lodErrorGiven = false;
    int level = 0;          // octree, noise: the level of detail of the whole surface
    // sage, wise: the paper's switches, each its default unless given.
    std::optional<bool> scanPolygons, estimateBox, points, bottomUp, cellTests, occlusion, capSeams;
    int metaCellSize = kDefaultMetaCellSize;
    int threads = 0;  // 0: the machine's cores (as many as the cache allows strips for)
    int prefetch = 32;
    int readers = BrickPrefetcher::kDefaultReaders;
    bool prefetchGiven = false, readersGiven = false;
    int prefetchNear = 2;  // BrickLookAhead::kNearBricks; RemoteReadAhead::kNear for a store at a URL
    uint64_t cacheMb = 1024;
    std::optional<bool> physicalMeshes;  // meshes in physical space (default) or volume space
    MeshPostOptions post;                // octree, noise: smooth, decimate, largest, min_piece
};

bool isViewDependent(const std::string& method);

// The threads a default extraction runs: the machine's cores.
int machineThreads();

// Checks each setting's range and the settings against each other (not against a store: see
// ExtractSession); throws SettingsError.
void checkExtractSettings(const ExtractSettings& s);

// How the brick cache is shared (threads, prefetch), `defaultThreads` when no thread count was
// given; throws CacheBudgetError (cache/brick_cache.h) when the cache is too small for them.
CachePlan planCache(const ExtractSettings& s, const BrickCache& cache, int defaultThreads);

// Readers and look-ahead for a store read over the network, unless given (RemoteReadAhead,
// core/extract/brick_look_ahead.h).
void adaptToRemoteStore(ExtractSettings& s);
// Readers for a store on this machine, unless given: the default, but no more than the cores
// beside the extraction's own thread (`cores`), and at least one. On 2 cores a second reader
// took the extraction's core: from the page cache, one-shot views were 5-29 % and 1-thread full
// extractions 6-37 % slower with two readers than with one; cold, one was as fast or faster
// (the 1024^3 head: 1 % slower; bench/log.md).
void adaptToLocalStore(ExtractSettings& s, int cores);

// The view-dependent options (sage or wise, with the switches given) for a plan.
ViewExtractOptions viewExtractOptions(const ExtractSettings& s, const CachePlan& plan);

}  // namespace vdiso
