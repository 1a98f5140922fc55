// The stores a server offers: each opened once, with one brick cache that every frame of
// every client reads through, and its description for the viewer (the `hello` message of
// docs/protocol.md).
#pragma once

#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "cache/brick_cache.h"
#include "core/lod/thin_parts.h"
#include "core/trees/meta_cell_range_cache.h"
#include "core/trees/minmax_tree.h"
#include "io/store/brick_store.h"
#include "serve/shared_chunks.h"

namespace vdiso::serve {

struct ServedStore {
    std::string name;  // the file name without its directory and ".vdiso"
    std::unique_ptr<BrickStoreReader> reader;
    std::unique_ptr<BrickCache> cache;
    // The meta-cell ranges of its bricks, kept across frames and clients (as many bricks as the
    // cache holds).
    std::unique_ptr<MetaCellRangeCache> ranges;
    std::unique_ptr<LostPartMemo> lostParts;  // as many bricks as the ranges
    // The min/max tree over every level's bricks, built once for every frame.
    std::unique_ptr<MinMaxTree> tree;
    // Its cacheable chunks as encoded once for every client (serve/shared_chunks.h).
    std::unique_ptr<SharedChunks> chunks;
    double defaultIso = 0;  // --iso, else Otsu's threshold of the histogram
    std::string description;  // the store's JSON object in `hello`
};

class StoreCatalog {
public:
    // Opens every store, a path or a URL (throws IoError naming the one that fails) and gives each a cache of
    // cacheBytes / stores.size() and shared chunks of chunkBytes / stores.size(). Two stores of the same
    // name are refused. Each store's min/max tree is built on `threads` threads.
    StoreCatalog(const std::vector<std::string>& paths, uint64_t cacheBytes, uint64_t chunkBytes,
                 std::optional<double> iso, const RemoteOptions& remote = {}, int threads = 1);

    size_t size() const { return mStores.size(); }
    ServedStore& operator[](size_t i) { return mStores[i]; }
    // {"type":"hello","version":1,"stores":[...],"session":"SESSION"}
    std::string hello(const std::string& session) const;

private:
    std::vector<ServedStore> mStores;
    std::string mStoresJson;  // [...]
};

}  // namespace vdiso::serve
