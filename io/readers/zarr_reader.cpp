#include "io/readers/zarr_reader.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <future>
#include <fstream>
#include <new>
#include <nlohmann/json.hpp>
#include <vector>

#include "core/interrupt.h"
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

ZarrArrayMeta readArrayMeta(const ZarrKeys& keys, const std::string& dir, int format) {
    const std::string name = format == 2 ? ".zarray" : "zarr.json", key = joinZarrKey(dir, name);
    const auto text = readText(keys, key);
    if (!text) throwIoError(dir.empty() ? keys.name() : keys.where(dir), "holds no " + name + ": not a Zarr array");
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
    glm::dvec3 spacing{1.0}, origin{0.0};
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
    image.arrayDir = relative.lexically_normal().generic_string();
    while (!image.arrayDir.empty() && image.arrayDir.back() == '/') image.arrayDir.pop_back();
    if (image.arrayDir == ".") image.arrayDir.clear();
    image.meta = readArrayMeta(keys, image.arrayDir, format);
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

class ZarrSliceReader final : public SliceReader {
public:
    ZarrSliceReader(std::string name, std::unique_ptr<ZarrKeys> keys, ZarrImage image, const VolumeInfo& info)
        : mName(std::move(name)), mKeys(std::move(keys)), mImage(std::move(image)), mInfo(info) {}

    const VolumeInfo& info() const override { return mInfo; }

    void read(void* dst, int64_t count) override {
        auto* out = static_cast<unsigned char*>(dst);
        const size_t sliceBytes = size_t(mInfo.sliceSamples()) * scalarSize(mInfo.type);
        const int64_t depth = mImage.meta.chunks[mImage.meta.chunks.size() - 3];
        for (int64_t s = 0; s < count; ++s, ++mNext) {
            if (mNext >= mInfo.dims[2]) throwIoError(mName, "has fewer slices than asked for");
            const int64_t layer = mNext / depth;
            if (layer != mLayerIndex) loadLayer(layer);
            std::memcpy(out + size_t(s) * sliceBytes,
                        mLayer.data() + size_t(mNext - layer * depth) * sliceBytes, sliceBytes);
        }
    }

    // Chunks are loaded by the read that needs them: passing over slices loads none.
    void skip(int64_t count) override {
        if (count < 0 || count > mInfo.dims[2] - mNext) throwIoError(mName, "has fewer slices than asked for");
        mNext += count;
    }

    std::string name() const override { return mName; }
    // A remote array is no file an output could overwrite.
    std::vector<std::string> files() const override {
        if (mKeys->isRemote()) return {};
        return {mImage.arrayDir.empty() ? mKeys->name() : mKeys->where(mImage.arrayDir)};
    }

private:
    void loadLayer(int64_t layer) {
        const ZarrArrayMeta& m = mImage.meta;
        const size_t n = m.shape.size();
        const int64_t cz = m.chunks[n - 3], cy = m.chunks[n - 2], cx = m.chunks[n - 1];
        const int64_t nx = mInfo.dims[0], ny = mInfo.dims[1];
        const int64_t z0 = layer * cz, depth = std::min(cz, mInfo.dims[2] - z0);
        const size_t outSize = scalarSize(mInfo.type), inSize = fileScalarSize(m.type);
        try {
            mLayer.resize(size_t(depth) * size_t(mInfo.sliceSamples()) * outSize);
            mChunk.resize(size_t(m.chunkBytes()));
        } catch (const std::bad_alloc&) {
            throwIoError(mName, "cannot hold a layer of chunks (" + std::to_string(depth) +
                                    " slices of " + std::to_string(nx) + " x " + std::to_string(ny) + ")");
        }
        const bool swap = m.bigEndian != hostIsBigEndian();
        const std::vector<std::string> keys = layerKeys(layer);
        const int64_t columns = (nx + cx - 1) / cx;
        auto decodeChunk = [&](size_t i, const std::optional<std::vector<unsigned char>>& bytes) {
            const int64_t y0 = int64_t(i) / columns * cy, x0 = int64_t(i) % columns * cx;
            const int64_t rows = std::min(cy, ny - y0), cols = std::min(cx, nx - x0);
            if (!bytes) {
                fillRegion(depth, x0, y0, cols, rows);
                return;
            }
            decodeZarrChunk(m, bytes->data(), bytes->size(), mChunk.data(), mKeys->where(keys[i]));
            for (int64_t lz = 0; lz < depth; ++lz)
                for (int64_t ly = 0; ly < rows; ++ly)
                    decodeSamples(mChunk.data() + size_t((lz * cy + ly) * cx) * inSize, m.type, swap,
                                  size_t(cols),
                                  mLayer.data() + size_t((lz * ny + y0 + ly) * nx + x0) * outSize,
                                  mInfo.type);
        };
        if (!mKeys->isRemote()) {  // a chunk at a time: memory stays the layer
            for (size_t i = 0; i < keys.size(); ++i) {
                throwIfInterrupted(mName);
                decodeChunk(i, mKeys->get(keys[i], chunkBound()));
            }
        } else {
            // Remote: the layer's chunks were fetched while the layer before was decoded (or
            // are fetched now), and the next layer's are fetched while this one is.
            ZarrKeys::Values values = mAheadLayer == layer ? mAhead.get() : mKeys->getAll(keys, chunkBound());
            mAheadLayer = -1;
            if ((layer + 1) * cz < mInfo.dims[2]) {
                mAheadLayer = layer + 1;
                mAhead = std::async(std::launch::async, [this, next = layerKeys(layer + 1)] {
                    return mKeys->getAll(next, chunkBound());
                });
            }
            for (size_t i = 0; i < keys.size(); ++i) decodeChunk(i, values[i]);
        }
        mLayerIndex = layer;
    }

    // The layer's chunk keys, a row of chunks after another.
    std::vector<std::string> layerKeys(int64_t layer) const {
        const ZarrArrayMeta& m = mImage.meta;
        const size_t n = m.shape.size();
        std::vector<int64_t> index(n, 0);
        index[n - 3] = layer;
        std::vector<std::string> keys;
        for (int64_t y = 0; y * m.chunks[n - 2] < mInfo.dims[1]; ++y)
            for (int64_t x = 0; x * m.chunks[n - 1] < mInfo.dims[0]; ++x) {
                index[n - 2] = y;
                index[n - 1] = x;
                keys.push_back(joinZarrKey(mImage.arrayDir, m.chunkKey(index)));
            }
        return keys;
    }

    // No encoding makes a chunk much larger than its samples: a bigger one is not one.
    uint64_t chunkBound() const { return mImage.meta.chunkBytes() + mImage.meta.chunkBytes() / 8 + 65536; }

    void fillRegion(int64_t depth, int64_t x0, int64_t y0, int64_t cols, int64_t rows) {
        const size_t outSize = scalarSize(mInfo.type);
        unsigned char value[8] = {};
        double fill = mImage.meta.fill;
        if (mInfo.type != ScalarType::F32 && !std::isfinite(fill)) fill = 0.0;
        decodeSamples(&fill, FileScalar::F64, false, 1, value, mInfo.type);
        const int64_t nx = mInfo.dims[0], ny = mInfo.dims[1];
        for (int64_t lz = 0; lz < depth; ++lz)
            for (int64_t ly = 0; ly < rows; ++ly) {
                unsigned char* row = mLayer.data() + size_t((lz * ny + y0 + ly) * nx + x0) * outSize;
                for (int64_t i = 0; i < cols; ++i) std::memcpy(row + size_t(i) * outSize, value, outSize);
            }
    }

    std::string mName;
    std::unique_ptr<ZarrKeys> mKeys;
    ZarrImage mImage;
    VolumeInfo mInfo;
    std::vector<unsigned char> mLayer, mChunk;
    int64_t mLayerIndex = -1;
    std::future<ZarrKeys::Values> mAhead;  // remote: the next layer's chunks, being fetched
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

std::unique_ptr<SliceReader> openZarrVolume(const std::string& path, int level, const RemoteOptions& remote) {
    auto keys = std::make_unique<ZarrKeys>(path, remote);
    ZarrImage image = locate(*keys, level);
    const std::string arrayWhere = image.arrayDir.empty() ? keys->name() : keys->where(image.arrayDir);
    VolumeInfo info;
    info.dims = spatialDims(image.meta, arrayWhere);
    requireVolumeDims(keys->name(), info.dims);
    info.type = storeTypeFor(image.meta.type, false);
    info.spacing = image.spacing;
    info.origin = image.origin;
    const std::string name = level == 0 ? keys->name() : keys->name() + " (level " + std::to_string(level) + ")";
    return std::make_unique<ZarrSliceReader>(name, std::move(keys), std::move(image), info);
}

}  // namespace vdiso
