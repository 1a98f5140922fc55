// How an extraction shares a brick cache between the bricks it pins and the ones it reads
// ahead, so that pins never fill the cache (a brick read ahead is not evicted before its use,
// and a traversal never waits for a slot no one will free).
//
// The prefetcher keeps what it read pinned until use: at most half the cache. Each image strip
// of a view-dependent extraction pins its brick and its share of that half (plus one being
// read): with at most a quarter of the cache's bricks in strips, pins never fill it. A cache
// holding every brick of the store never evicts, so then anything goes.
#pragma once

#include <cstdint>

#include "cache/brick_cache.h"

namespace vdiso {

struct CachePlan {
    int prefetchBricks = 0;  // bricks read ahead (what was asked, or what fits)
    int threads = 1;         // extraction threads
};

// The bricks a cache must hold for one frame: its pins (at most `prefetch` read ahead and
// waiting, and per image strip its brick and one being read) never fill it when at most half
// the cache is read ahead and at most a quarter of its bricks are strips. k frames extracting at
// once need k times this (a cache holding every brick of its store never evicts: any number).
uint64_t frameCacheBricks(int prefetch, int strips);

// `threads`: what the user asked for, or 0 for the default (`defaultThreads`, lowered to what
// the cache allows). Throws CacheBudgetError naming the cache size needed when an asked thread
// count does not fit.
CachePlan planCacheUse(const BrickCache& cache, bool viewDependent, int prefetch, int threads,
                       int defaultThreads);

// The counters of what happened between two readings of BrickCache::counters().
CacheCounters operator-(const CacheCounters& after, const CacheCounters& before);

}  // namespace vdiso
