// What a store is, from its header and index alone (no brick is read): what `vdiso info`
// prints and the Python module's Store.info() returns.
#pragma once

#include <cstdint>
#include <optional>
#include <vector>

#include "io/store/brick_store.h"
#include "io/json.h"

namespace vdiso {

struct ActiveBricks {
    size_t bricks = 0;
    uint64_t storedBytes = 0;
};

// Level 0's bricks that can hold iso (a span-space query over the bricks' value ranges).
ActiveBricks activeBricks(const BrickStoreReader& store, double iso);

// Stored bytes of each level's bricks, level 0 first.
std::vector<uint64_t> levelBytes(const BrickStoreReader& store);

// What `vdiso info` derives beyond the header: each level's stored bytes, the compression
// ratio (samples' bytes over the file's), and with `iso` the active bricks.
struct StoreFacts {
    std::vector<uint64_t> levelBytes;
    double compressionRatio = 0;
    std::optional<ActiveBricks> active;
};
StoreFacts storeFacts(const BrickStoreReader& store, std::optional<double> iso);

// A quantile of the store's histogram; integer samples get integer quantiles.
double storeQuantile(const BrickStoreReader& store, double fraction);

// `vdiso info --json`: dims, type, spacing, origin, orientation, bricks, levels, compression,
// value range, quantiles, histogram; with `iso`, the active bricks and their bytes.
JsonObject storeInfoJson(const BrickStoreReader& store, std::optional<double> iso = std::nullopt);

}  // namespace vdiso
