#include "io/readers/zarr_reader.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <future>
#include <map>
#include <mutex>
#include <fstream>
#include <new>
#include <stdexcept>
#include <vector>

#include <nlohmann/json.hpp>
#include <tbb/parallel_for.h>

#include "core/interrupt.h"
#include "io/crc32.h"
#include "io/error.h"
#include "io/readers/zarr_array.h"
#include "io/readers/zarr_keys.h"

namespace vdiso {
namespace {

using nlohmann::json;
namespace fs = std::filesystem;

constexpr size_t kMaxMetadataBytes = size_t(64) << 20;

bool isFile(const fs::path& p) {
    std::error_code ec;
    return fs::is_regular_file(p, ec);
}

// A metadata document's text, or nullopt when the key does not exist.
std::optional<std::string> readText(const ZarrKeys& keys, const std::string& key) {
    const auto bytes = keys.get(key, kMaxMetadataBytes);
    if (!bytes) return std::nullopt;
    return std::string(bytes->begin(), bytes->end());
}

json parseJson(const ZarrKeys& keys, const std::string& key, const std::string& text) {
    try {
        return json::parse(text);
    } catch (const json::exception& e) {
        throwIoError(keys.where(key), std::string("is not valid JSON: ") + e.what());
    }
}

ZarrArrayMeta readArrayMeta(const ZarrKeys& keys, const std::string& dir, int format, uint32_t* crc = nullptr) {
    const std::string name = format == 2 ? ".zarray" : "zarr.json", key = joinZarrKey(dir, name);
    const auto text = readText(keys, key);
    if (!text) throwIoError(dir.empty() ? keys.name() : keys.where(dir), "holds no " + name + ": not a Zarr array");
    if (crc) *crc = crc32Of(text->data(), text->size());
    return parseZarrArrayMeta(*text, format, keys.where(key));
}

// The three spatial axes of an array: its last three, the ones before them of size 1.
Dims3 spatialDims(const ZarrArrayMeta& m, const std::string& where) {
    const size_t n = m.shape.size();
    if (n < 3) throwIoError(where, "is " + std::to_string(n) + "-D: a volume needs 3 axes (z, y, x)");
    for (size_t a = 0; a + 3 < n; ++a)
        if (m.shape[a] != 1)
            throwIoError(where, "axis " + std::to_string(a) + " (before z, y, x) has " +
                                    std::to_string(m.shape[a]) +
                                    " entries: only one time point and channel can be read");
    return {m.shape[n - 1], m.shape[n - 2], m.shape[n - 3]};
}

// Applies OME-Zarr coordinate transformations (scale, translation, in order) to the spatial axes.
void applyTransforms(const json& list, size_t n, glm::dvec3& spacing, glm::dvec3& origin,
                     const std::string& where) {
    if (list.is_null()) return;
    if (!list.is_array()) throwIoError(where, "coordinateTransformations is not a list");
    for (const json& t : list) {
        const std::string type = t.is_object() ? t.value("type", std::string()) : "";
        if (type == "identity") continue;
        if (type != "scale" && type != "translation")
            throwIoError(where, "coordinate transformation \"" + type + "\" is not supported");
        const json& v = t.contains(type) ? t[type] : json();
        if (!v.is_array() || v.size() != n)
            throwIoError(where, "the " + type + " transformation has " +
                                    std::to_string(v.is_array() ? v.size() : 0) +
                                    " values for " + std::to_string(n) + " axes");
        for (int a = 0; a < 3; ++a) {
            const json& x = v[n - 1 - size_t(a)];
            if (!x.is_number() || !std::isfinite(x.get<double>()))
                throwIoError(where, "the " + type + " transformation holds " + x.dump());
            const double value = x.get<double>();
            if (type == "scale") {
                if (!(value > 0.0)) throwIoError(where, "a scale of " + x.dump() + " is not positive");
                spacing[a] *= value;
                origin[a] *= value;
            } else {
                origin[a] += value;
            }
        }
    }
}

struct ZarrImage {
    std::string arrayDir;  // the array's key prefix ("" for the root)
    ZarrArrayMeta meta;
    uint32_t metadataCrc = 0;  // of the array's metadata document
    glm::dvec3 spacing{1.0}, origin{0.0};
    int levels = 1;  // the multiscale's datasets (1 for a plain array)
};

// "0 (512 x 512 x 300), 1 (256 x 256 x 150)": the levels, for a level out of range.
std::string levelList(const ZarrKeys& keys, const json& datasets, int format) {
    std::string text;
    for (size_t i = 0; i < datasets.size(); ++i) {
        text += (i ? ", " : "") + std::to_string(i);
        try {
            const ZarrArrayMeta m = readArrayMeta(keys, datasets[i].value("path", std::string()), format);
            const Dims3 d = spatialDims(m, "");
            text += " (" + std::to_string(d[0]) + " x " + std::to_string(d[1]) + " x " +
                    std::to_string(d[2]) + ")";
        } catch (const std::exception&) {
        }
    }
    return text;
}

ZarrImage openMultiscale(const ZarrKeys& keys, const json& multiscales, int format, int level,
                         const std::string& where) {
    if (!multiscales.is_array() || multiscales.empty() || !multiscales[0].is_object())
        throwIoError(where, "has no multiscales image metadata");
    const json& ms = multiscales[0];
    const json datasets = ms.value("datasets", json());
    if (!datasets.is_array() || datasets.empty()) throwIoError(where, "its multiscales list no datasets");
    if (level < 0 || size_t(level) >= datasets.size())
        throwIoError(where, "has no level " + std::to_string(level) + "; its levels are " +
                                levelList(keys, datasets, format));
    const json& ds = datasets[size_t(level)];
    const std::string path = ds.is_object() ? ds.value("path", std::string()) : "";
    const fs::path relative(path);
    if (path.empty() || relative.is_absolute() ||
        std::any_of(relative.begin(), relative.end(), [](const fs::path& p) { return p == ".."; }))
        throwIoError(where, "dataset path \"" + path + "\" does not name a folder inside the image");
    ZarrImage image;
    image.levels = int(datasets.size());
    image.arrayDir = relative.lexically_normal().generic_string();
    while (!image.arrayDir.empty() && image.arrayDir.back() == '/') image.arrayDir.pop_back();
    if (image.arrayDir == ".") image.arrayDir.clear();
    image.meta = readArrayMeta(keys, image.arrayDir, format, &image.metadataCrc);
    const size_t n = image.meta.shape.size();
    const json axes = ms.value("axes", json());
    if (axes.is_array() && axes.size() == n && n >= 3)
        for (size_t a = n - 3; a < n; ++a)
            if (axes[a].is_object() && axes[a].contains("type") && axes[a]["type"] != "space")
                throwIoError(where, "axis " + axes[a].dump() + " is not spatial: the last three "
                                    "axes must be z, y, x");
    applyTransforms(ds.value("coordinateTransformations", json()), n, image.spacing, image.origin, where);
    applyTransforms(ms.value("coordinateTransformations", json()), n, image.spacing, image.origin, where);
    return image;
}

ZarrImage locate(const ZarrKeys& keys, int level) {
    const std::string& path = keys.name();
    auto plain = [&](int format, const std::string& text) {
        if (level != 0)
            throwIoError(path, "is a plain Zarr array: it has no level " + std::to_string(level));
        ZarrImage image;
        image.meta = parseZarrArrayMeta(text, format, keys.where(format == 2 ? ".zarray" : "zarr.json"));
        image.metadataCrc = crc32Of(text.data(), text.size());
        return image;
    };
    try {
        if (const auto text = readText(keys, ".zarray")) return plain(2, *text);
        if (const auto text = readText(keys, "zarr.json")) {
            const json j = parseJson(keys, "zarr.json", *text);
            if (!j.is_object()) throwIoError(path, "zarr.json is not a JSON object");
            if (j.value("node_type", std::string()) == "array") return plain(3, *text);
            const json attributes = j.value("attributes", json::object());
            const json ome = attributes.is_object() ? attributes.value("ome", json::object()) : json();
            const json ms = ome.is_object() && ome.contains("multiscales") ? ome["multiscales"]
                                                                           : attributes.value("multiscales", json());
            return openMultiscale(keys, ms, 3, level, path);
        }
        if (const auto text = readText(keys, ".zattrs")) {
            const json attributes = parseJson(keys, ".zattrs", *text);
            if (!attributes.is_object()) throwIoError(path, ".zattrs is not a JSON object");
            return openMultiscale(keys, attributes.value("multiscales", json()), 2, level, path);
        }
    } catch (const json::exception& e) {
        throwIoError(path, std::string("its metadata has a field of the wrong kind: ") + e.what());
    }
    throwIoError(path, "holds no Zarr metadata (.zarray, .zattrs or zarr.json)");
}

// No encoding makes a chunk much larger than its samples: a bigger one is not one.
uint64_t chunkBound(const ZarrArrayMeta& m) { return m.chunkBytes() + m.chunkBytes() / 8 + 65536; }

class ZarrSliceReader final : public SliceReader {
public:
    ZarrSliceReader(std::unique_ptr<ZarrVolume> volume, std::vector<ZarrChunkPin>* pins, int64_t pinnedLayers)
        : mVolume(std::move(volume)), mPins(pins), mPinnedLayers(pinnedLayers) {
        if (mPins && mPinnedLayers == 0) mPins->assign(size_t(mVolume->chunkCount()), ZarrChunkPin{});
        if (mPins && mPins->size() != size_t(mVolume->chunkCount()))
            throw std::logic_error("zarr reader: pins of another chunk grid");
    }

    const VolumeInfo& info() const override { return mVolume->info(); }

    void read(void* dst, int64_t count) override {
        auto* out = static_cast<unsigned char*>(dst);
        const VolumeInfo& info = mVolume->info();
        const size_t sliceBytes = size_t(info.sliceSamples()) * scalarSize(info.type);
        const Dims3& chunk = mVolume->chunkShape();
        const int64_t cx = chunk[0], cy = chunk[1], cz = chunk[2];
        const int64_t nx = info.dims[0], ny = info.dims[1];
        const size_t sampleBytes = scalarSize(info.type), chunkBytes = mVolume->decodedBytes();
        for (int64_t s = 0; s < count; ++s, ++mNext) {
            if (mNext >= info.dims[2]) throwIoError(name(), "has fewer slices than asked for");
            const int64_t layer = mNext / cz, lz = mNext - layer * cz;
            if (layer != mLayerIndex) loadLayer(layer);
            // The slice's rows from the layer's decoded chunks, each chunk's part of a row at once.
            unsigned char* slice = out + size_t(s) * sliceBytes;
            const unsigned char* decoded = mLayer.data();
            for (int64_t y0 = 0; y0 < ny; y0 += cy) {
                const int64_t rows = std::min(cy, ny - y0);
                for (int64_t x0 = 0; x0 < nx; x0 += cx, decoded += chunkBytes) {
                    const size_t cols = size_t(std::min(cx, nx - x0)) * sampleBytes;
                    for (int64_t ly = 0; ly < rows; ++ly)
                        std::memcpy(slice + size_t((y0 + ly) * nx + x0) * sampleBytes,
                                    decoded + size_t((lz * cy + ly) * cx) * sampleBytes, cols);
                }
            }
        }
    }

    // Chunks are loaded by the read that needs them: passing over slices loads none.
    void skip(int64_t count) override {
        if (count < 0 || count > mVolume->info().dims[2] - mNext) throwIoError(name(), "has fewer slices than asked for");
        mNext += count;
    }

    std::string name() const override { return mVolume->name(); }
    // A remote array is no file an output could overwrite.
    std::vector<std::string> files() const override {
        if (mVolume->isRemote()) return {};
        return {mVolume->arrayName()};
    }

private:
    // Decodes the layer's chunks (in parallel) into mLayer, one after another in layerChunks'
    // order, each whole (edge chunks padded as stored): read() takes slices from them.
    void loadLayer(int64_t layer) {
        const VolumeInfo& info = mVolume->info();
        const int64_t cz = mVolume->chunkShape()[2];
        const std::vector<Dims3> chunks = layerChunks(layer);
        const size_t chunkBytes = mVolume->decodedBytes();
        try {
            mLayer.resize(chunks.size() * chunkBytes);
        } catch (const std::bad_alloc&) {
            throwIoError(name(), "cannot hold a layer of chunks (" + std::to_string(chunks.size()) + " chunks of " +
                                     std::to_string(chunkBytes) + " bytes)");
        }
        auto place = [&](size_t i, const std::optional<std::vector<unsigned char>>& bytes) {
            const Dims3& c = chunks[i];
            if (mPins) {
                const ZarrChunkPin pin = bytes ? ZarrChunkPin{bytes->size(), crc32Of(bytes->data(), bytes->size())}
                                               : ZarrChunkPin{};
                ZarrChunkPin& slot = (*mPins)[size_t(mVolume->chunkNumber(c))];
                if (c[2] < mPinnedLayers && slot != pin)
                    throwIoError(mVolume->where(c), "changed since the interrupted run that is being resumed read "
                                                    "it; run vdiso index again with --restart");
                slot = pin;
            }
            mVolume->decode(c, bytes, mLayer.data() + i * chunkBytes);
        };
        if (!mVolume->isRemote()) {  // a chunk read at a time on each core
            tbb::parallel_for(size_t(0), chunks.size(), [&](size_t i) {
                throwIfInterrupted(name());
                place(i, mVolume->stored({chunks[i]})[0]);
            });
        } else {
            // Remote: the layer's chunks were fetched while the layer before was decoded (or
            // are fetched now), and the next layer's are fetched while this one is.
            auto values = mAheadLayer == layer ? mAhead.get() : mVolume->stored(chunks);
            mAheadLayer = -1;
            if ((layer + 1) * cz < info.dims[2]) {
                mAheadLayer = layer + 1;
                mAhead = std::async(std::launch::async, [this, next = layerChunks(layer + 1)] {
                    return mVolume->stored(next);
                });
            }
            tbb::parallel_for(size_t(0), chunks.size(), [&](size_t i) { place(i, values[i]); });
        }
        mLayerIndex = layer;
    }

    // The layer's chunks, a row after another.
    std::vector<Dims3> layerChunks(int64_t layer) const {
        std::vector<Dims3> chunks;
        for (int64_t y = 0; y < mVolume->chunkCounts()[1]; ++y)
            for (int64_t x = 0; x < mVolume->chunkCounts()[0]; ++x) chunks.push_back({x, y, layer});
        return chunks;
    }

    std::unique_ptr<ZarrVolume> mVolume;
    std::vector<ZarrChunkPin>* mPins;
    int64_t mPinnedLayers;
    std::vector<unsigned char> mLayer;  // the layer's chunks, decoded
    int64_t mLayerIndex = -1;
    std::future<std::vector<std::optional<std::vector<unsigned char>>>> mAhead;  // remote: the next layer's
    int64_t mAheadLayer = -1;
    int64_t mNext = 0;
};

}  // namespace

bool looksLikeZarr(const std::string& dir) {
    const fs::path root(dir);
    for (const char* name : {".zarray", ".zgroup", ".zattrs", "zarr.json"})
        if (isFile(root / name)) return true;
    return false;
}

struct ZarrVolume::Image : ZarrImage {};

ZarrVolume::ZarrVolume(const std::string& path, int level, const RemoteOptions& remote)
    : mKeys(std::make_unique<ZarrKeys>(path, remote)), mImage(std::make_unique<Image>()) {
    static_cast<ZarrImage&>(*mImage) = locate(*mKeys, level);
    const ZarrArrayMeta& m = mImage->meta;
    mInfo.dims = spatialDims(m, arrayName());
    requireVolumeDims(mKeys->name(), mInfo.dims);
    mInfo.type = storeTypeFor(m.type, false);
    mInfo.spacing = mImage->spacing;
    mInfo.origin = mImage->origin;
    const size_t n = m.shape.size();
    for (int a = 0; a < 3; ++a) {
        mChunkShape[a] = m.chunks[n - 1 - size_t(a)];
        mChunkCounts[a] = (mInfo.dims[a] + mChunkShape[a] - 1) / mChunkShape[a];
    }
    mMetadataCrc = mImage->metadataCrc;
    mName = level == 0 ? mKeys->name() : mKeys->name() + " (level " + std::to_string(level) + ")";
}

ZarrVolume::~ZarrVolume() = default;

bool ZarrVolume::isRemote() const { return mKeys->isRemote(); }
int ZarrVolume::levelCount() const { return mImage->levels; }
uint64_t ZarrVolume::requests() const { return mKeys->requests(); }
uint64_t ZarrVolume::bytesFetched() const { return mKeys->bytesFetched(); }
size_t ZarrVolume::decodedBytes() const {
    return size_t(mChunkShape[0] * mChunkShape[1] * mChunkShape[2]) * scalarSize(mInfo.type);
}

// A chunk's place: its key (a sharded array's shard) and, sharded, its number in the shard.
struct ZarrVolume::Place {
    std::string key;
    uint64_t inner = 0;
};

ZarrVolume::Place ZarrVolume::place(const Dims3& c) const {
    const ZarrArrayMeta& m = mImage->meta;
    std::vector<int64_t> index(m.shape.size(), 0);
    for (int a = 0; a < 3; ++a) index[index.size() - 1 - size_t(a)] = c[a];
    Place p;
    if (!m.shards.empty())
        for (size_t a = 0; a < index.size(); ++a) {  // C order inside the shard
            const int64_t perShard = m.shards[a] / m.chunks[a];
            p.inner = p.inner * uint64_t(perShard) + uint64_t(index[a] % perShard);
            index[a] /= perShard;
        }
    p.key = joinZarrKey(mImage->arrayDir, m.chunkKey(index));
    return p;
}

std::string ZarrVolume::arrayName() const {
    return mImage->arrayDir.empty() ? mKeys->name() : mKeys->where(mImage->arrayDir);
}

std::string ZarrVolume::where(const Dims3& c) const {
    const Place p = place(c);
    if (mImage->meta.shards.empty()) return mKeys->where(p.key);
    return mKeys->where(p.key) + " (inner chunk " + std::to_string(p.inner) + ")";
}

std::vector<std::optional<std::vector<unsigned char>>> ZarrVolume::stored(const std::vector<Dims3>& chunks) const {
    const ZarrArrayMeta& m = mImage->meta;
    std::vector<Place> places;
    places.reserve(chunks.size());
    for (const Dims3& c : chunks) places.push_back(place(c));
    if (m.shards.empty()) {
        if (places.size() == 1) return {mKeys->get(places[0].key, chunkBound(m))};
        std::vector<std::string> keys;
        for (const Place& p : places) keys.push_back(p.key);
        return mKeys->getAll(keys, chunkBound(m));
    }
    // Sharded: each shard opened once, its index read (once, then kept), its inner chunks read
    // by ranges, neighbours in the shard in one read.
    std::vector<std::optional<std::vector<unsigned char>>> out(chunks.size());
    std::map<std::string, std::vector<size_t>> byShard;
    for (size_t i = 0; i < places.size(); ++i) byShard[places[i].key].push_back(i);
    std::vector<const std::pair<const std::string, std::vector<size_t>>*> shards;
    for (const auto& entry : byShard) shards.push_back(&entry);
    mKeys->forEach(shards.size(), [&](size_t s) {
        const std::string& key = shards[s]->first;
        const std::shared_ptr<const ZarrKeys::Object> object = shardObject(key);
        if (!object) return;  // a missing shard: every inner chunk the fill value
        const std::shared_ptr<const std::vector<uint64_t>> index = shardIndex(key, *object);
        std::vector<size_t> wanted = shards[s]->second;
        std::sort(wanted.begin(), wanted.end(), [&](size_t a, size_t b) {
            return (*index)[2 * places[a].inner] < (*index)[2 * places[b].inner];
        });
        for (size_t k = 0; k < wanted.size();) {
            const uint64_t first = (*index)[2 * places[wanted[k]].inner];
            if (first == ~uint64_t(0)) {  // not stored
                ++k;
                continue;
            }
            // A run of inner chunks stored one after another.
            uint64_t end = first + (*index)[2 * places[wanted[k]].inner + 1];
            size_t last = k + 1;
            while (last < wanted.size() && (*index)[2 * places[wanted[last]].inner] == end) {
                end += (*index)[2 * places[wanted[last]].inner + 1];
                ++last;
            }
            if (end - first > chunkBound(m) * (last - k))
                throwIoError(where(chunks[wanted[k]]), "is larger than any encoding of its samples");
            std::vector<unsigned char> run(size_t(end - first));
            object->read(first, run.size(), run.data());
            for (size_t j = k; j < last; ++j) {
                const uint64_t at = (*index)[2 * places[wanted[j]].inner] - first;
                const uint64_t n = (*index)[2 * places[wanted[j]].inner + 1];
                out[wanted[j]].emplace(run.begin() + ptrdiff_t(at), run.begin() + ptrdiff_t(at + n));
            }
            k = last;
        }
    });
    return out;
}

std::shared_ptr<const ZarrKeys::Object> ZarrVolume::shardObject(const std::string& key) const {
    auto opened = [&]() -> std::shared_ptr<const ZarrKeys::Object> {
        std::optional<ZarrKeys::Object> object = mKeys->open(key, 0);
        return object ? std::make_shared<const ZarrKeys::Object>(std::move(*object)) : nullptr;
    };
    if (!mKeys->isRemote()) return opened();  // a file: opened for the read (a folder of shards has many)
    {
        std::lock_guard lock(mShardMutex);
        if (auto it = mShardObjects.find(key); it != mShardObjects.end()) return it->second;
    }
    std::shared_ptr<const ZarrKeys::Object> object = opened();
    std::lock_guard lock(mShardMutex);
    return mShardObjects.emplace(key, std::move(object)).first->second;
}

std::shared_ptr<const std::vector<uint64_t>> ZarrVolume::shardIndex(const std::string& key,
                                                                   const ZarrKeys::Object& object) const {
    {
        std::lock_guard lock(mShardMutex);
        if (auto it = mShardIndexes.find(key); it != mShardIndexes.end()) return it->second;
    }
    const ZarrArrayMeta& m = mImage->meta;
    const uint64_t count = m.chunksPerShard(), bytes = m.shardIndexBytes();
    const std::string where = mKeys->where(key);
    if (object.size() < bytes)
        throwIoError(where, "is " + std::to_string(object.size()) + " bytes, too short for its shard index of " +
                                std::to_string(bytes));
    std::vector<unsigned char> raw(static_cast<size_t>(bytes));
    object.read(m.indexAtEnd ? object.size() - bytes : 0, raw.size(), raw.data());
    if (m.indexCrc) {
        uint32_t crc;
        std::memcpy(&crc, raw.data() + count * 16, 4);
        if (crc != crc32cOf(raw.data(), count * 16))
            throwIoError(where, "has a damaged shard index (its CRC-32C does not match)");
    }
    auto index = std::make_shared<std::vector<uint64_t>>(size_t(2 * count));
    std::memcpy(index->data(), raw.data(), size_t(count * 16));
    // Every stored inner chunk lies among the shard's chunk bytes, outside its index.
    const uint64_t lo = m.indexAtEnd ? 0 : bytes, hi = m.indexAtEnd ? object.size() - bytes : object.size();
    for (uint64_t i = 0; i < count; ++i) {
        const uint64_t offset = (*index)[2 * i], n = (*index)[2 * i + 1];
        if (offset == ~uint64_t(0) && n == ~uint64_t(0)) continue;
        if (offset < lo || offset > hi || n > hi - offset || n == 0)
            throwIoError(where, "has a damaged shard index: inner chunk " + std::to_string(i) + " at bytes " +
                                    std::to_string(offset) + " + " + std::to_string(n) + ", outside its chunks' bytes " +
                                    std::to_string(lo) + ".." + std::to_string(hi));
    }
    std::lock_guard lock(mShardMutex);
    mShardIndexes.emplace(key, index);
    return index;
}

void ZarrVolume::decode(const Dims3& c, const std::optional<std::vector<unsigned char>>& bytes,
                        unsigned char* out) const {
    const ZarrArrayMeta& m = mImage->meta;
    const size_t samples = size_t(mChunkShape[0] * mChunkShape[1] * mChunkShape[2]);
    const size_t sampleBytes = scalarSize(mInfo.type);
    if (!bytes) {  // the fill value, as the specification says
        unsigned char value[8] = {};
        double fill = m.fill;
        if (mInfo.type != ScalarType::F32 && !std::isfinite(fill)) fill = 0.0;
        decodeSamples(&fill, FileScalar::F64, false, 1, value, mInfo.type);
        for (size_t i = 0; i < samples; ++i) std::memcpy(out + i * sampleBytes, value, sampleBytes);
        return;
    }
    const bool swap = m.bigEndian != hostIsBigEndian();
    if (fileScalarSize(m.type) == sampleBytes && !swap && storeTypeFor(m.type, false) == mInfo.type &&
        (m.type == FileScalar::U8 || m.type == FileScalar::U16 || m.type == FileScalar::I16 || m.type == FileScalar::F32)) {
        decodeZarrChunk(m, bytes->data(), bytes->size(), out, where(c));  // already the store's samples
        return;
    }
    thread_local std::vector<unsigned char> raw;
    raw.resize(size_t(m.chunkBytes()));
    decodeZarrChunk(m, bytes->data(), bytes->size(), raw.data(), where(c));
    decodeSamples(raw.data(), m.type, swap, samples, out, mInfo.type);
}

std::unique_ptr<SliceReader> zarrSliceReader(std::unique_ptr<ZarrVolume> volume, std::vector<ZarrChunkPin>* pins,
                                             int64_t pinnedLayers) {
    return std::make_unique<ZarrSliceReader>(std::move(volume), pins, pinnedLayers);
}

std::unique_ptr<SliceReader> openZarrVolume(const std::string& path, int level, const RemoteOptions& remote,
                                            std::vector<ZarrChunkPin>* pins) {
    return zarrSliceReader(std::make_unique<ZarrVolume>(path, level, remote), pins);
}

}  // namespace vdiso
