#include "serve/store_catalog.h"

#include <algorithm>
#include <filesystem>

#include "core/camera.h"
#include "core/view_presets.h"
#include "io/error.h"
#include "io/json.h"
#include "serve/protocol.h"

namespace vdiso::serve {

namespace {

bool isUtf8(const std::string& text) {
    for (size_t i = 0; i < text.size();) {
        const unsigned char c = static_cast<unsigned char>(text[i]);
        const int extra = c < 0x80 ? 0 : (c >> 5) == 6 ? 1 : (c >> 4) == 14 ? 2 : (c >> 3) == 30 ? 3 : -1;
        if (extra < 0 || i + size_t(extra) > text.size() - 1) return false;
        for (int k = 1; k <= extra; ++k)
            if ((static_cast<unsigned char>(text[i + size_t(k)]) >> 6) != 2) return false;
        i += size_t(extra) + 1;
    }
    return true;
}

std::string vec3(const glm::dvec3& v) {
    const double values[3] = {v.x, v.y, v.z};
    return jsonArray(values);
}

std::string describe(const ServedStore& s) {
    const VolumeInfo& v = s.reader->volume();
    const StoreHeader& h = s.reader->header();
    const ValueHistogram& histogram = s.reader->histogram();
    std::string counts = "[";
    for (size_t b = 0; b < histogram.counts.size(); ++b)
        counts += (b ? ", " : "") + std::to_string(histogram.counts[b]);
    counts += "]";
    JsonObject o;
    o.add("name", s.name);
    o.addRaw("dims", vec3(glm::dvec3(v.dims[0], v.dims[1], v.dims[2])));
    o.addRaw("spacing", vec3(v.spacing)).addRaw("origin", vec3(v.origin));
    o.addRaw("boundsMin", vec3(v.origin)).addRaw("boundsMax", vec3(v.worldMax()));
    o.add("type", scalarTypeName(v.type));
    // Where the volume lies in the patient, and the facing its presets take (anterior for an
    // oriented volume, core/camera.h), in volume space: the page frames its presets with it.
    std::string direction = "[";
    for (int c = 0; c < 3; ++c) direction += (c ? ", " : "") + vec3(v.direction[c]);
    o.add("hasOrientation", v.hasOrientation).addRaw("direction", direction + "]");
    const ViewFacing facing = viewFacing(std::nullopt, v);
    o.addRaw("facing", JsonObject().addRaw("toEye", vec3(facing.toEye)).addRaw("up", vec3(facing.up))
                           .addRaw("front", vec3(facing.front)).str());
    // Exact: the page sends these back as isovalues, which the server checks against the range.
    o.addExact("valueMin", h.valueMin).addExact("valueMax", h.valueMax).addExact("iso", s.defaultIso);
    o.add("brickSize", int64_t(h.brickSize)).add("bricks", s.reader->layout().brickCount());
    o.addRaw("histogram",
             JsonObject().addExact("lo", histogram.lo).addExact("hi", histogram.hi).addRaw("counts", counts).str());
    return o.str();
}

}  // namespace

StoreCatalog::StoreCatalog(const std::vector<std::string>& paths, uint64_t cacheBytes, uint64_t chunkBytes,
                           std::optional<double> iso, const RemoteOptions& remote, int threads) {
    if (paths.empty()) throw IoError("no store to serve");
    mStores.reserve(paths.size());
    for (const std::string& location : paths) {
        const std::string path = displayLocation(location);
        ServedStore s;
        s.name = std::filesystem::path(path).stem().string();
        // Names go to browsers in text messages, which must be UTF-8 (one bad byte and the
        // browser drops the connection).
        if (!isUtf8(s.name))
            throw IoError(path + ": the store's name is not UTF-8; rename the file to serve it");
        for (const ServedStore& other : mStores)
            if (other.name == s.name)
                throw IoError(path + ": a store named '" + s.name + "' is served already");
        s.reader = std::make_unique<BrickStoreReader>(location, StoreOpenOptions{ReadMode::Buffered, remote});
        if (uint64_t(s.reader->index().size()) >= kNoBrick)
            throw IoError(path + ": " + std::to_string(s.reader->index().size()) +
                          " bricks; the protocol numbers bricks in 32 bits");
        const StoreHeader& h = s.reader->header();
        if (iso && !(*iso >= h.valueMin && *iso <= h.valueMax))
            throw IoError(path + ": the isovalue " + std::to_string(*iso) + " is outside the store's values [" +
                          std::to_string(h.valueMin) + ", " + std::to_string(h.valueMax) + "]");
        s.defaultIso = iso ? *iso : s.reader->histogram().otsuThreshold();
        s.cache = std::make_unique<BrickCache>(*s.reader, cacheBytes / paths.size());
        s.ranges = std::make_unique<MetaCellRangeCache>(s.cache->budgetBytes() / s.reader->brickBytes());
        s.lostParts = std::make_unique<LostPartMemo>(s.cache->budgetBytes() / s.reader->brickBytes());
        s.tree = std::make_unique<MinMaxTree>(s.cache->levels(), s.cache->brickRanges(), threads);
        s.chunks = std::make_unique<SharedChunks>(chunkBytes / paths.size());
        s.description = describe(s);
        mStores.push_back(std::move(s));
    }
    mStoresJson = "[";
    for (size_t i = 0; i < mStores.size(); ++i) mStoresJson += (i ? ", " : "") + mStores[i].description;
    mStoresJson += "]";
}

std::string StoreCatalog::hello(const std::string& session) const {
    return "{\"type\": \"hello\", \"version\": " + std::to_string(kProtocolVersion) + ", \"stores\": " + mStoresJson +
           ", \"session\": " + jsonQuote(session) + "}";
}

}  // namespace vdiso::serve
