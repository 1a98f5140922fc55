#include "serve/serve_options.h"

#include <algorithm>
#include <string>

#include <unistd.h>

#include "core/kernel/brick_extractor.h"
#include "core/settings_error.h"

namespace vdiso::serve {

void checkServeOptions(const ServeOptions& o) {
    if (o.stores.empty()) throw SettingsError("stores", "expects at least one store");
    if (o.threads < 1 || o.threads > 64)
        throw SettingsError("threads", "expects 1 to 64 image strips a frame, not " + std::to_string(o.threads));
    if (o.metaCellSize < 1 || o.metaCellSize > kMaxMetaCellSize)
        throw SettingsError("metacell", "expects 1 to " + std::to_string(kMaxMetaCellSize) + " cells, not " +
                                            std::to_string(o.metaCellSize));
    if (!(o.lodError >= 0 && o.lodError <= 1e6))
        throw SettingsError("lod_error", "expects pixels, 0 or more, not " + std::to_string(o.lodError));
    if (!o.token.empty() &&
        (o.token.size() < 16 || o.token.find_first_not_of("0123456789abcdefABCDEF-_") != std::string::npos))
        throw SettingsError("token", "expects at least 16 characters of hex digits, '-' or '_'");
    if (o.cacheBytes == 0) throw SettingsError("cache_mb", "expects a brick cache of 1 MB or more");
    if (!(o.writeTimeoutSeconds > 0 && o.writeTimeoutSeconds <= 3600))
        throw SettingsError("write_timeout", "expects seconds above 0 and at most 3600, not " +
                                                 std::to_string(o.writeTimeoutSeconds));
    if (o.maxViewers < 0 || o.maxViewers > 100000)
        throw SettingsError("max_viewers", "expects 1 to 100000 viewers (0: from the memory), not " +
                                               std::to_string(o.maxViewers));
}

int defaultMaxViewers(uint64_t cacheBytes) {
    const uint64_t memory = uint64_t(sysconf(_SC_PHYS_PAGES)) * uint64_t(sysconf(_SC_PAGE_SIZE));
    const uint64_t left = memory > cacheBytes ? memory - cacheBytes : 0;
    return int(std::clamp<uint64_t>(left / kViewerBytes, 4, 256));
}

ServeOptions withDefaults(ServeOptions o) {
    if (o.maxViewers == 0) o.maxViewers = defaultMaxViewers(o.cacheBytes);
    return o;
}

}  // namespace vdiso::serve
