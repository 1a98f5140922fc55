#include "serve/store_catalog.h"

#include <algorithm>
#include <filesystem>

#include "io/error.h"
#include "io/json.h"
#include "serve/protocol.h"

namespace vdiso::serve {

namespace {

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
    o.add("valueMin", h.valueMin).add("valueMax", h.valueMax).add("iso", s.defaultIso);
    o.add("brickSize", int64_t(h.brickSize)).add("bricks", s.reader->layout().brickCount());
    o.addRaw("histogram", JsonObject().add("lo", histogram.lo).add("hi", histogram.hi).addRaw("counts", counts).str());
    return o.str();
}

}  // namespace

StoreCatalog::StoreCatalog(const std::vector<std::string>& paths, uint64_t cacheBytes,
                           std::optional<double> iso) {
    if (paths.empty()) throw IoError("no store to serve");
    mStores.reserve(paths.size());
    for (const std::string& path : paths) {
        ServedStore s;
        s.name = std::filesystem::path(path).stem().string();
        for (const ServedStore& other : mStores)
            if (other.name == s.name)
                throw IoError(path + ": a store named '" + s.name + "' is served already");
        s.reader = std::make_unique<BrickStoreReader>(path);
        if (uint64_t(s.reader->layout().brickCount()) >= kNoBrick)
            throw IoError(path + ": " + std::to_string(s.reader->layout().brickCount()) +
                          " bricks; the protocol numbers bricks in 32 bits");
        const StoreHeader& h = s.reader->header();
        if (iso && !(*iso >= h.valueMin && *iso <= h.valueMax))
            throw IoError(path + ": --iso " + std::to_string(*iso) + " is outside the store's values [" +
                          std::to_string(h.valueMin) + ", " + std::to_string(h.valueMax) + "]");
        s.defaultIso = iso ? *iso : s.reader->histogram().otsuThreshold();
        s.cache = std::make_unique<BrickCache>(*s.reader, cacheBytes / paths.size());
        s.description = describe(s);
        mStores.push_back(std::move(s));
    }
    mHello = "{\"type\": \"hello\", \"version\": " + std::to_string(kProtocolVersion) + ", \"stores\": [";
    for (size_t i = 0; i < mStores.size(); ++i) mHello += (i ? ", " : "") + mStores[i].description;
    mHello += "]}";
}

}  // namespace vdiso::serve
