#include "serve/serve_settings.h"

#include <algorithm>
#include <thread>

#include "cache/cache_plan.h"

namespace vdiso::serve {

SessionSettings sessionSettings(const ServeOptions& o, StoreCatalog& stores) {
    // Two readers a frame however many strips: with 2 frames of 2 strips on 2 cores, 4 readers
    // a frame made 13 threads for no more frames a second (bench/log.md, "Many viewers").
    SessionSettings s;
    s.view.method = "sage";
    s.view.threads = o.threads;
    s.view.metaCellSize = o.metaCellSize;
    s.view.prefetch = 8;
    s.view.readers = std::max(1, 2 / o.threads);
    s.view.lodError = o.lodError;
    s.outboxBytes = o.outboxBytes;
    for (size_t i = 0; i < stores.size(); ++i)
        if (stores[i].reader->readsRemotely()) {
            adaptToRemoteStore(s.view);
            break;
        }
    return s;
}

int frameSlots(StoreCatalog& stores, const SessionSettings& settings) {
    // As many as keep the cores busy: a frame's strips each take a core; more frames at once
    // only share them (each slower), and the waiting ones go in turn, first passes first
    // (FramePool). With one strip a frame, at least two, so that a first pass need not wait for
    // a whole final one. Where bricks come over the network a frame mostly waits: four a core.
    const int cores = int(std::max(1u, std::thread::hardware_concurrency()));
    bool remote = false;
    for (size_t i = 0; i < stores.size(); ++i) remote = remote || stores[i].reader->readsRemotely();
    const int perCore = remote ? 4 : 1;
    int slots = std::max(2, perCore * cores);
    for (size_t i = 0; i < stores.size(); ++i) {
        const BrickCache& cache = *stores[i].cache;
        const uint64_t bricks = cache.budgetBytes() / stores[i].reader->brickBytes();
        if (bricks >= uint64_t(stores[i].reader->index().size())) continue;
        const uint64_t perFrame = frameCacheBricks(settings.view.prefetch, settings.view.threads);
        if (bricks < perFrame)
            throw CacheBudgetError(stores[i].reader->path() + ": a brick cache of " + std::to_string(bricks) +
                                   " bricks cannot hold what one frame pins (" + std::to_string(perFrame) +
                                   " bricks of " + std::to_string(stores[i].reader->brickBytes() >> 10) +
                                   " KB with " + std::to_string(settings.view.threads) + " threads a frame)");
        slots = std::min<int>(slots, int(bricks / perFrame));
    }
    return slots;
}

}  // namespace vdiso::serve
