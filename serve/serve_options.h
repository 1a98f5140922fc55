// What `vdiso serve` and vdiso.serve are given: the stores, the address, the budgets, the
// viewers' limits and timeouts; their one check (checkServeOptions, which the server's
// constructor runs before opening a store) and the defaults it fills in.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "core/kernel/brick_extractor.h"
#include "io/remote/remote_options.h"

namespace vdiso::serve {

struct ServeOptions {
    std::vector<std::string> stores;  // paths or URLs
    RemoteOptions remote;             // for stores at URLs
    std::optional<double> iso;  // every store's default isovalue; else Otsu's threshold
    std::string host = "127.0.0.1";
    uint16_t port = 8080;  // 0: the system chooses
    uint64_t cacheBytes = uint64_t(1024) << 20;  // brick cache, split across the stores
    // Encoded cacheable chunks kept for every viewer (serve/shared_chunks.h), split likewise.
    uint64_t chunkCacheBytes = uint64_t(256) << 20;
    int threads = 1;  // image strips per frame
    int metaCellSize = kDefaultMetaCellSize;
    double lodError = 1.0;  // levels of detail: the final frame's error in pixels; 0: level 0 only
    std::string webRoot;  // the viewer's folder (web/)
    std::string token;    // empty: a random one
    bool handleSignals = false;  // SIGINT and SIGTERM stop run()
    // Viewers at once; one more is answered 503. 0: defaultMaxViewers().
    int maxViewers = 0;
    // A viewer's outgoing queue holds at most this many bytes (serve/outbox.h).
    size_t outboxBytes = size_t(32) << 20;
    // A write to a viewer that has not completed in this long (a client that stopped reading)
    // drops the viewer: its memory is freed, its frame slot and pins released.
    double writeTimeoutSeconds = 30;
};

// Viewers a server takes at once by default: what the machine's memory holds beside the brick
// cache at kViewerBytes each (a session's outgoing bound, its frame's mesh and chunk buffers),
// between 4 and 256.
constexpr uint64_t kViewerBytes = uint64_t(96) << 20;
int defaultMaxViewers(uint64_t cacheBytes);

// Checks each option's range (threads, meta-cell size, level-of-detail error, token, at least
// one store); throws SettingsError (core/settings_error.h) naming it. Server's constructor calls it.
void checkServeOptions(const ServeOptions& options);

// The options with their defaults filled in (maxViewers).
ServeOptions withDefaults(ServeOptions options);

}  // namespace vdiso::serve
