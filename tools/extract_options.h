// vdiso extract's options: parsed once for vdiso and for vdiso-mpi, which takes the same
// command line under mpirun, and the cameras they ask for.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "cache/brick_cache.h"
#include "cache/cache_plan.h"
#include "core/brick_extractor.h"
#include "core/brick_prefetcher.h"
#include "core/camera.h"
#include "core/extract_view.h"
#include "core/mesh_slabs.h"
#include "core/volume.h"
#include "io/remote/remote_options.h"

namespace vdiso::cli {

// The text of 'vdiso extract --help'.
extern const char* const kExtractHelp;

struct ExtractOptions {
    std::string input;
    std::optional<bool> scanPolygons, estimateBox, points, bottomUp, cellTests, occlusion, capSeams;  // sage/wise
    std::string pointsPath;
    bool oracle = false;
    int orbitFrames = 0;   // --path orbit:N
    std::string pathFile;  // --path FILE.json
    std::optional<double> iso;
    double lodError = 1.0;
    bool lodErrorGiven = false;
    int level = 0;
    std::string method = "octree";
    std::string meshPath, pngPath, statsPath, cameraPath;
    ViewChoice view;
    bool viewGiven = false;
    std::optional<bool> physicalMeshes;  // --mesh-space; default physical
    int width = 800, height = 800;
    int metaCellSize = kDefaultMetaCellSize;
    int threads = 0;  // 0: the machine's cores (as many as the cache allows strips for)
    int prefetch = 32;
    int readers = BrickPrefetcher::kDefaultReaders;
    bool prefetchGiven = false, readersGiven = false;
    int prefetchNear = 2;  // BrickLookAhead::kNearBricks; kRemoteNear for a store at a URL
    RemoteOptions remote;  // for a store at a URL
    uint64_t cacheMb = 1024;
    bool overwrite = false, quiet = false, cold = false, help = false;
    bool meshCompress = false;  // --mesh-compress (.glb only)
    MeshPostOptions post;       // --smooth, --decimate, --largest, --min-piece
};

bool isViewDependent(const std::string& method);

// Parses vdiso extract's arguments (argv[0] is "extract") and checks them against each other;
// throws UsageError. With --help or -h, returns at once with `help` set.
ExtractOptions parseExtractOptions(int argc, char** argv);

// How the brick cache is shared (threads, prefetch) for these options, `defaultThreads` when
// --threads was not given; throws UsageError naming --cache-mb when it is too small.
CachePlan planCache(const ExtractOptions& o, const BrickCache& cache, int defaultThreads);

// Readers and look-ahead for a store read over the network, unless given: a request waits a
// round trip where a disk read waits a seek, so more are kept in flight
// (kRemoteReaders per strip, kRemotePrefetch bricks ahead, of which kRemoteNear are read
// before they are known to show).
constexpr int kRemoteReaders = 16, kRemotePrefetch = 128, kRemoteNear = 32;
void adaptToRemoteStore(ExtractOptions& o);

// The view-dependent options (sage or wise, with the switches given) for a plan.
ViewExtractOptions viewExtractOptions(const ExtractOptions& o, const CachePlan& plan);

// The cameras the options ask for over `volume`: one (--camera, --view or its default), the
// frames of a --path, or none (a full method without a picture); each with its clip planes.
// `view`: the preset used, with the side a store with orientation defaults to.
std::vector<Camera> extractCameras(const ExtractOptions& o, const VolumeInfo& volume, ViewChoice& view);

}  // namespace vdiso::cli
