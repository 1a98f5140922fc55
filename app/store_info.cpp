#include "app/store_info.h"

#include <cmath>
#include <span>
#include <string>

#include "core/orientation.h"
#include "core/trees/span_space.h"
#include "io/store/external_bricks.h"

namespace vdiso {

// Level 0's bricks that can hold iso.
ActiveBricks activeBricks(const BrickStoreReader& store, double iso) {
    const std::span<const BrickEntry> index(store.index().data(), size_t(store.layout().brickCount()));
    std::vector<float> mins(index.size()), maxs(index.size());
    for (size_t i = 0; i < index.size(); ++i) {
        mins[i] = index[i].minValue;
        maxs[i] = index[i].maxValue;
    }
    const SpanSpaceTree tree(mins, maxs);
    std::vector<uint32_t> ids;
    tree.query(iso, ids);
    ActiveBricks a;
    a.bricks = ids.size();
    for (uint32_t id : ids) a.storedBytes += index[id].storedBytes;
    return a;
}

// Stored bytes of each level's bricks.
std::vector<uint64_t> levelBytes(const BrickStoreReader& store) {
    std::vector<uint64_t> bytes;
    for (const BrickLevel& level : store.levels()) {
        uint64_t sum = 0;
        for (int64_t id = 0; id < level.layout.brickCount(); ++id)
            sum += store.index()[size_t(level.firstBrick + id)].storedBytes;
        bytes.push_back(sum);
    }
    return bytes;
}

double storeQuantile(const BrickStoreReader& store, double fraction) {
    const double q = store.histogram().quantile(fraction);
    return store.volume().type == ScalarType::F32 ? q : std::round(q);
}

StoreFacts storeFacts(const BrickStoreReader& store, std::optional<double> iso) {
    StoreFacts f;
    f.levelBytes = levelBytes(store);
    f.compressionRatio = double(store.volume().byteSize()) / double(store.fileBytes());
    if (iso) f.active = activeBricks(store, *iso);
    return f;
}

JsonObject storeInfoJson(const BrickStoreReader& store, std::optional<double> iso) {
    const StoreHeader& h = store.header();
    const VolumeInfo& v = h.volume;
    const BrickLayout& l = store.layout();
    const ValueHistogram& hist = store.histogram();
    const StoreFacts facts = storeFacts(store, iso);
    const double ratio = facts.compressionRatio;
    const std::vector<uint64_t>& bytesOfLevel = facts.levelBytes;
    const std::optional<ActiveBricks>& active = facts.active;
    auto quantile = [&](double f) { return storeQuantile(store, f); };
    auto triple = [](const auto& t) {
        return "[" + std::to_string(t[0]) + ", " + std::to_string(t[1]) + ", " +
               std::to_string(t[2]) + "]";
    };
    JsonObject o;
    o.add("file", store.path()).add("format_version", int64_t(h.formatVersion));
    o.addRaw("dims", triple(v.dims)).add("type", scalarTypeName(v.type));
    o.addRaw("spacing", "[" + std::to_string(v.spacing.x) + ", " + std::to_string(v.spacing.y) +
                            ", " + std::to_string(v.spacing.z) + "]");
    o.addRaw("origin", "[" + std::to_string(v.origin.x) + ", " + std::to_string(v.origin.y) +
                           ", " + std::to_string(v.origin.z) + "]");
    // Columns: the LPS direction of the i, j and k axes (identity without orientation).
    std::string direction = "[";
    for (int c = 0; c < 3; ++c)
        direction += (c ? ", " : "") + std::string("[") + std::to_string(v.direction[c].x) + ", " +
                     std::to_string(v.direction[c].y) + ", " + std::to_string(v.direction[c].z) + "]";
    o.add("has_orientation", v.hasOrientation).addRaw("direction", direction + "]");
    if (v.hasOrientation) o.add("axes_toward", axisSidesCode(v.direction));
    o.add("brick_size", h.brickSize).addRaw("brick_counts", triple(l.brickCounts));
    o.add("bricks", l.brickCount()).add("compression", compressionName(h.compression));
    o.add("volume_bytes", v.byteSize()).add("file_bytes", store.fileBytes());
    if (store.external())  // level 0 lies there, and the levels after it that come from the data's own scales
        o.add("indexes", store.external()->name()).add("indexed_levels", store.external()->levelCount());
    std::string levels = "[";
    for (size_t k = 0; k < bytesOfLevel.size(); ++k) {
        const BrickLevel& level = store.levels()[k];
        JsonObject lo;
        lo.add("level", int64_t(k)).addRaw("dims", triple(level.volume.dims));
        lo.add("cell_size", double(int64_t(1) << k)).add("bricks", level.layout.brickCount());
        lo.add("stored_bytes", bytesOfLevel[k]);
        levels += (k ? ", " : "") + lo.str();
    }
    o.addRaw("levels", levels + "]");
    o.add("compression_ratio", ratio).add("min", h.valueMin).add("max", h.valueMax);
    o.add("p01", quantile(0.01)).add("p50", quantile(0.5)).add("p99", quantile(0.99));
    std::string counts = "[";
    for (int b = 0; b < kHistogramBins; ++b)
        counts += (b ? "," : "") + std::to_string(hist.counts[size_t(b)]);
    o.addRaw("histogram", counts + "]");
    if (active) {
        o.add("iso", *iso).add("active_bricks", uint64_t(active->bricks));
        o.add("active_bytes", active->storedBytes);
    }
    return o;
}

}  // namespace vdiso
