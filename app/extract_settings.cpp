#include "app/extract_settings.h"

#include <algorithm>
#include <cmath>
#include <thread>

#include "core/extract/brick_look_ahead.h"
#include "core/kernel/brick_extractor.h"
#include "core/brick_levels.h"

namespace vdiso {

bool isViewDependent(const std::string& method) { return method == "sage" || method == "wise"; }

int machineThreads() { return int(std::max(1u, std::thread::hardware_concurrency())); }

void checkExtractSettings(const ExtractSettings& s) {
    if (s.method != "octree" && s.method != "noise" && s.method != "sage" && s.method != "wise")
        throw SettingsError("method", "expects octree, noise, sage or wise, not '" + s.method + "'");
    if (!s.iso) throw SettingsError("iso", "is needed: the isovalue to extract");
    if (!std::isfinite(*s.iso)) throw SettingsError("iso", "expects a finite isovalue, not " + std::to_string(*s.iso));
    if (!(s.lodError >= 0 && s.lodError <= 1e6))
        throw SettingsError("lod_error", "expects pixels, 0 or more, not " + std::to_string(s.lodError));
    if (s.level < 0 || s.level >= kMaxLevels)
        throw SettingsError("level", "expects a level of detail from 0 to " + std::to_string(kMaxLevels - 1) +
                                         ", not " + std::to_string(s.level));
    if (s.metaCellSize < 1 || s.metaCellSize > kMaxMetaCellSize)
        throw SettingsError("metacell", "expects 1 to " + std::to_string(kMaxMetaCellSize) + " cells, not " +
                                            std::to_string(s.metaCellSize));
    if (s.threads < 0 || s.threads > 256)
        throw SettingsError("threads", "expects 1 to 256 threads, not " + std::to_string(s.threads));
    if (s.cacheMb < 1) throw SettingsError("cache_mb", "expects a brick cache of 1 MB or more");
    if (!(s.post.decimateRatio > 0 && s.post.decimateRatio <= 1))
        throw SettingsError("decimate", "expects the fraction of triangles to keep, above 0 and at most 1, not " +
                                            std::to_string(s.post.decimateRatio));
    if (s.post.smoothIterations < 0 || s.post.smoothIterations > 1000)
        throw SettingsError("smooth", "expects 0 to 1000 iterations, not " + std::to_string(s.post.smoothIterations));
    const bool viewDependent = isViewDependent(s.method);
    if (!viewDependent && (s.scanPolygons || s.estimateBox || s.points || s.bottomUp || s.cellTests ||
                           s.occlusion || s.capSeams))
        throw SettingsError("scan, box, points, update, cell_test, occlusion and seams",
                            "apply to the view-dependent methods, sage and wise");
    if (s.lodErrorGiven && !viewDependent)
        throw SettingsError("lod_error", "applies to the view-dependent methods, sage and wise; the full "
                                         "methods take one level of detail for the whole surface");
    if (s.level != 0 && viewDependent)
        throw SettingsError("level", "applies to the full methods, octree and noise; sage and wise choose a "
                                     "level per part of the volume by the level-of-detail error");
    if (s.post.any() && viewDependent)
        throw SettingsError("smooth, decimate, largest and min_piece",
                            "apply to the full surface: the methods octree and noise");
}

CachePlan planCache(const ExtractSettings& s, const BrickCache& cache, int defaultThreads) {
    return planCacheUse(cache, isViewDependent(s.method), s.prefetch, s.threads, defaultThreads);
}

void adaptToRemoteStore(ExtractSettings& s) {
    if (!s.readersGiven) s.readers = RemoteReadAhead::kReaders;
    if (!s.prefetchGiven) s.prefetch = RemoteReadAhead::kBricks;
    s.prefetchNear = RemoteReadAhead::kNear;
}

void adaptToLocalStore(ExtractSettings& s, int cores) {
    if (!s.readersGiven) s.readers = std::clamp(cores - 1, 1, BrickPrefetcher::kDefaultReaders);
}

ViewExtractOptions viewExtractOptions(const ExtractSettings& s, const CachePlan& plan) {
    ViewExtractOptions v = s.method == "sage" ? ViewExtractOptions::sage(*s.iso) : ViewExtractOptions::wise(*s.iso);
    v.metaCellSize = s.metaCellSize;
    if (s.scanPolygons) v.scanPolygons = *s.scanPolygons;
    if (s.estimateBox) v.estimateBox = *s.estimateBox;
    if (s.points) v.points = *s.points;
    if (s.bottomUp) v.bottomUp = *s.bottomUp;
    if (s.cellTests) v.cellTests = *s.cellTests;
    if (s.occlusion) v.occlusion = *s.occlusion;
    if (s.capSeams) v.capSeams = *s.capSeams;
    v.prefetchBricks = plan.prefetchBricks;
    v.prefetchReaders = s.readers;
    v.prefetchNear = s.prefetchNear;
    v.threads = plan.threads;
    v.lodError = s.lodError;
    return v;
}

}  // namespace vdiso
