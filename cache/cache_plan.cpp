#include "cache/cache_plan.h"

#include <algorithm>
#include <stdexcept>
#include <string>

namespace vdiso {

uint64_t frameCacheBricks(int prefetch, int strips) {
    return std::max(2 * uint64_t(std::max(prefetch, 0)), 4 * uint64_t(std::max(strips, 1)));
}

CachePlan planCacheUse(const BrickCache& cache, bool viewDependent, int prefetch, int threads,
                       int defaultThreads) {
    const uint64_t brickBytes = cache.store().brickBytes();
    const uint64_t slots = cache.budgetBytes() / brickBytes;
    const bool holdsAll = slots >= uint64_t(cache.store().index().size());
    CachePlan plan;
    plan.prefetchBricks = int(std::min<uint64_t>(uint64_t(std::max(prefetch, 0)), slots / 2));
    // frameCacheBricks(prefetch, strips) <= slots, prefetch lowered first, then the strips.
    const uint64_t maxStrips = holdsAll ? UINT64_MAX : std::max<uint64_t>(1, slots / 4);
    if (threads == 0) {
        plan.threads = viewDependent ? int(std::min<uint64_t>(uint64_t(defaultThreads), maxStrips)) : defaultThreads;
    } else {
        if (viewDependent && uint64_t(threads) > maxStrips)
            throw CacheBudgetError(std::to_string(threads) + " image strips need a brick cache of " +
                                   std::to_string(frameCacheBricks(0, threads)) + " bricks; it holds " + std::to_string(slots) +
                                   " of " + std::to_string(brickBytes >> 10) + " KB");
        plan.threads = threads;
    }
    plan.threads = std::max(plan.threads, 1);
    return plan;
}

CacheCounters operator-(const CacheCounters& a, const CacheCounters& b) {
    CacheCounters d;
    d.requests = a.requests - b.requests;
    d.hits = a.hits - b.hits;
    d.misses = a.misses - b.misses;
    d.evictions = a.evictions - b.evictions;
    d.bytesRead = a.bytesRead - b.bytesRead;
    d.readSeconds = a.readSeconds - b.readSeconds;
    d.decodeSeconds = a.decodeSeconds - b.decodeSeconds;
    return d;
}

}  // namespace vdiso
