#include "tests/zarr_test_util.h"

#include <blosc.h>
#include <zstd.h>

#include <cstring>
#include <optional>

#include <gtest/gtest.h>

#include "io/crc32.h"
#include "io/store/brick_store.h"
#include "io/readers/sample_decode.h"
#include "tests/reader_test_util.h"
#include "tests/test_util.h"

namespace vdiso::test {
namespace {

std::string codecJsonV2(Codec c) {
    switch (c) {
        case Codec::None: return "null";
        case Codec::Blosc: return R"({"id": "blosc", "cname": "lz4", "clevel": 5, "shuffle": 1, "blocksize": 0})";
        case Codec::Zstd: return R"({"id": "zstd", "level": 3})";
        case Codec::Gzip: return R"({"id": "gzip", "level": 6})";
    }
    return "null";
}

std::string codecJsonV3(Codec c) {
    switch (c) {
        case Codec::None: return "";
        case Codec::Blosc: return R"(, {"name": "blosc", "configuration": {"cname": "lz4", "clevel": 5, "shuffle": "shuffle", "typesize": 2, "blocksize": 0}})";
        case Codec::Zstd: return R"(, {"name": "zstd", "configuration": {"level": 3, "checksum": false}})";
        case Codec::Gzip: return R"(, {"name": "gzip", "configuration": {"level": 6}})";
    }
    return "";
}

std::string joinInts(const std::vector<int64_t>& v) {
    std::string s;
    for (size_t i = 0; i < v.size(); ++i) s += (i ? ", " : "") + std::to_string(v[i]);
    return s;
}

}  // namespace

double zarrTestValue(int64_t x, int64_t y, int64_t z) { return double((x * 7 + y * 131 + z * 1031) % 65536); }

std::string compress(const std::string& raw, Codec codec) {
    switch (codec) {
        case Codec::None: return raw;
        case Codec::Gzip: return gzipBytes(raw);
        case Codec::Zstd: {
            std::string out(ZSTD_compressBound(raw.size()), '\0');
            out.resize(ZSTD_compress(out.data(), out.size(), raw.data(), raw.size(), 3));
            return out;
        }
        case Codec::Blosc: {
            std::string out(raw.size() + BLOSC_MAX_OVERHEAD, '\0');
            const int n = blosc_compress_ctx(5, BLOSC_SHUFFLE, 2, raw.size(), raw.data(), out.data(),
                                             out.size(), "lz4", 0, 1);
            out.resize(size_t(n));
            return out;
        }
    }
    return raw;
}

void writeArray(const std::filesystem::path& dir, const ArraySpec& a) {
    std::filesystem::create_directories(dir);
    std::vector<int64_t> shape(size_t(a.extraAxes), 1), chunks(size_t(a.extraAxes), 1);
    shape.insert(shape.end(), {a.dims[2], a.dims[1], a.dims[0]});
    chunks.insert(chunks.end(), a.chunk.begin(), a.chunk.end());
    std::vector<int64_t> grid = chunks;  // the chunk grid's chunks: shards when sharded
    std::string codecs = R"({"name": "bytes", "configuration": {"endian": ")" +
                         std::string(a.bigEndian ? "big" : "little") + "\"}}" + codecJsonV3(a.codec);
    if (!a.shard.empty()) {
        grid.assign(size_t(a.extraAxes), 1);
        grid.insert(grid.end(), a.shard.begin(), a.shard.end());
        codecs = R"({"name": "sharding_indexed", "configuration": {"chunk_shape": [)" + joinInts(chunks) +
                 R"(], "codecs": [)" + codecs +
                 R"(], "index_codecs": [{"name": "bytes", "configuration": {"endian": "little"}}, {"name": "crc32c"}], )"
                 R"("index_location": "end"}})";
    }
    if (a.format == 2) {
        writeFile((dir / ".zarray").string(),
                        std::string(R"({"zarr_format": 2, "shape": [)") + joinInts(shape) +
                            R"(], "chunks": [)" + joinInts(chunks) + R"(], "dtype": ")" +
                            (a.bigEndian ? ">u2" : "<u2") + R"(", "compressor": )" +
                            codecJsonV2(a.codec) + R"(, "fill_value": )" +
                            std::to_string(int(a.fill)) + R"(, "order": "C", "filters": null, )" +
                            R"("dimension_separator": ")" + std::string(1, a.separator) + "\"}");
    } else {
        writeFile((dir / "zarr.json").string(),
                        std::string(R"({"zarr_format": 3, "node_type": "array", "shape": [)") +
                            joinInts(shape) + R"(], "data_type": "uint16", "chunk_grid": {"name": )" +
                            R"("regular", "configuration": {"chunk_shape": [)" + joinInts(grid) +
                            R"(]}}, "chunk_key_encoding": {"name": "default", "configuration": )" +
                            R"({"separator": ")" + std::string(1, a.separator) + R"("}}, "fill_value": )" +
                            std::to_string(int(a.fill)) + R"(, "codecs": [)" + codecs + "]}");
    }
    const int64_t cz = a.chunk[0], cy = a.chunk[1], cx = a.chunk[2];
    // Inner chunk (kx, ky, kz)'s stored bytes, or nullopt when skipped or outside the array.
    auto encoded = [&](int64_t kx, int64_t ky, int64_t kz) -> std::optional<std::string> {
        if (kx * cx >= a.dims[0] || ky * cy >= a.dims[1] || kz * cz >= a.dims[2]) return std::nullopt;
        if (a.skip && a.skip(kx, ky, kz)) return std::nullopt;
        std::vector<double> samples;
        for (int64_t z = kz * cz; z < (kz + 1) * cz; ++z)
            for (int64_t y = ky * cy; y < (ky + 1) * cy; ++y)
                for (int64_t x = kx * cx; x < (kx + 1) * cx; ++x)
                    samples.push_back(x < a.dims[0] && y < a.dims[1] && z < a.dims[2]
                                          ? a.sample(x * a.step, y * a.step, z * a.step)
                                          : 0.0);  // padding of edge chunks
        return compress(encodeSamples(samples, FileScalar::U16, a.bigEndian), a.codec);
    };
    auto fileOf = [&](int64_t kx, int64_t ky, int64_t kz) {
        std::vector<int64_t> index(size_t(a.extraAxes), 0);
        index.insert(index.end(), {kz, ky, kx});
        std::string key = a.format == 3 ? "c" : "";
        for (int64_t i : index) key += (key.empty() ? "" : std::string(1, a.separator)) + std::to_string(i);
        const std::filesystem::path file = dir / key;
        std::filesystem::create_directories(file.parent_path());
        return file.string();
    };
    if (a.shard.empty()) {
        for (int64_t kz = 0; kz * cz < a.dims[2]; ++kz)
            for (int64_t ky = 0; ky * cy < a.dims[1]; ++ky)
                for (int64_t kx = 0; kx * cx < a.dims[0]; ++kx)
                    if (const auto bytes = encoded(kx, ky, kz)) writeFile(fileOf(kx, ky, kz), *bytes);
        return;
    }
    const int64_t rz = a.shard[0] / cz, ry = a.shard[1] / cy, rx = a.shard[2] / cx;
    for (int64_t sz = 0; sz * a.shard[0] < a.dims[2]; ++sz)
        for (int64_t sy = 0; sy * a.shard[1] < a.dims[1]; ++sy)
            for (int64_t sx = 0; sx * a.shard[2] < a.dims[0]; ++sx) {
                std::string shard;
                std::vector<uint64_t> index;
                for (int64_t pz = 0; pz < rz; ++pz)
                    for (int64_t py = 0; py < ry; ++py)
                        for (int64_t px = 0; px < rx; ++px) {
                            const auto bytes = encoded(sx * rx + px, sy * ry + py, sz * rz + pz);
                            index.push_back(bytes ? shard.size() : ~uint64_t(0));
                            index.push_back(bytes ? bytes->size() : ~uint64_t(0));
                            if (bytes) shard += *bytes;
                        }
                std::string tail(index.size() * 8, '\0');
                std::memcpy(tail.data(), index.data(), tail.size());
                const uint32_t crc = crc32cOf(tail.data(), tail.size());
                tail.append(reinterpret_cast<const char*>(&crc), 4);
                writeFile(fileOf(sx, sy, sz), shard + tail);
            }
}

void expectSameStore(const BrickStoreReader& index, const BrickStoreReader& store, const std::string& what) {
    ASSERT_EQ(index.levels().size(), store.levels().size()) << what;
    ASSERT_EQ(index.index().size(), store.index().size()) << what;
    EXPECT_EQ(index.volume().dims, store.volume().dims) << what;
    EXPECT_EQ(index.histogram().counts, store.histogram().counts) << what;
    const auto a = index.subBlockCodes(), b = store.subBlockCodes();
    ASSERT_EQ(a.size(), b.size());
    for (size_t i = 0; i < a.size(); ++i)
        ASSERT_TRUE(a[i].lo == b[i].lo && a[i].hi == b[i].hi) << what << ": sub-block " << i;
    std::vector<unsigned char> x(index.brickBytes()), y(store.brickBytes());
    for (int64_t id = 0; id < int64_t(store.index().size()); ++id) {
        EXPECT_EQ(index.index()[size_t(id)].minValue, store.index()[size_t(id)].minValue) << what << ": brick " << id;
        EXPECT_EQ(index.index()[size_t(id)].maxValue, store.index()[size_t(id)].maxValue) << what << ": brick " << id;
        index.readBrick(id, x.data());
        store.readBrick(id, y.data());
        ASSERT_EQ(x, y) << what << ": brick " << id;
    }
}

}  // namespace vdiso::test
