#include "io/readers/zarr_array.h"

#include <blosc.h>
#include <zlib.h>
#include <zstd.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <nlohmann/json.hpp>

#include "core/checked_math.h"
#include "io/error.h"

namespace vdiso {
namespace {

using nlohmann::json;

constexpr uint64_t kMaxChunkBytes = uint64_t(1) << 30;

// The field `key` of `j`, which must be there.
const json& field(const json& j, const char* key, const std::string& where) {
    const auto it = j.find(key);
    if (it == j.end()) throwIoError(where, std::string("has no \"") + key + "\"");
    return *it;
}

// "64 x 64 x 64": a chunk shape in the file's axis order.
std::string chunkShapeText(const std::vector<int64_t>& chunks) {
    std::string text;
    for (size_t a = 0; a < chunks.size(); ++a) text += (a ? " x " : "") + std::to_string(chunks[a]);
    return text;
}

std::vector<int64_t> integers(const json& j, const char* what, const std::string& where) {
    if (!j.is_array()) throwIoError(where, std::string("\"") + what + "\" is not an array");
    std::vector<int64_t> v;
    for (const json& x : j) {
        if (!x.is_number_integer()) throwIoError(where, std::string("\"") + what + "\" holds a non-integer");
        v.push_back(x.get<int64_t>());
    }
    return v;
}

// v2 dtype: "<u2", "|u1", ">f4", ...
void parseDtype(const std::string& dtype, ZarrArrayMeta& m, const std::string& where) {
    if (dtype.size() < 3) throwIoError(where, "dtype \"" + dtype + "\" is not a NumPy type string");
    const char order = dtype[0], kind = dtype[1];
    const std::string size = dtype.substr(2);
    m.bigEndian = order == '>';
    static const std::pair<const char*, FileScalar> kTypes[] = {
        {"i1", FileScalar::I8},  {"u1", FileScalar::U8},  {"i2", FileScalar::I16},
        {"u2", FileScalar::U16}, {"i4", FileScalar::I32}, {"u4", FileScalar::U32},
        {"f4", FileScalar::F32}, {"f8", FileScalar::F64}};
    for (const auto& [name, type] : kTypes)
        if (std::string(1, kind) + size == name && (order == '<' || order == '>' || order == '|')) {
            m.type = type;
            return;
        }
    throwIoError(where, "dtype \"" + dtype + "\" is not supported (8, 16 and 32-bit integers, "
                        "32 and 64-bit floats)");
}

void parseDataType(const std::string& name, ZarrArrayMeta& m, const std::string& where) {
    static const std::pair<const char*, FileScalar> kTypes[] = {
        {"int8", FileScalar::I8},   {"uint8", FileScalar::U8},   {"int16", FileScalar::I16},
        {"uint16", FileScalar::U16}, {"int32", FileScalar::I32}, {"uint32", FileScalar::U32},
        {"float32", FileScalar::F32}, {"float64", FileScalar::F64}};
    for (const auto& [n, type] : kTypes)
        if (name == n) {
            m.type = type;
            return;
        }
    throwIoError(where, "data_type \"" + name + "\" is not supported (8, 16 and 32-bit integers, "
                        "32 and 64-bit floats)");
}

double parseFill(const json& j, const std::string& where) {
    if (j.is_null()) return 0.0;
    if (j.is_number()) return j.get<double>();
    if (j.is_boolean()) return j.get<bool>() ? 1.0 : 0.0;
    if (j.is_string()) {
        const std::string s = j.get<std::string>();
        if (s == "NaN") return std::numeric_limits<double>::quiet_NaN();
        if (s == "Infinity") return std::numeric_limits<double>::infinity();
        if (s == "-Infinity") return -std::numeric_limits<double>::infinity();
    }
    throwIoError(where, "fill_value " + j.dump() + " is not supported");
}

ZarrCompressor compressorNamed(const std::string& id, const std::string& where) {
    if (id == "blosc") return ZarrCompressor::Blosc;
    if (id == "zstd") return ZarrCompressor::Zstd;
    if (id == "gzip" || id == "zlib") return ZarrCompressor::Gzip;
    throwIoError(where, "compressor \"" + id + "\" is not supported (blosc, zstd, gzip, zlib)");
}

void parseV2(const json& j, ZarrArrayMeta& m, const std::string& where) {
    m.shape = integers(field(j, "shape", where), "shape", where);
    m.chunks = integers(field(j, "chunks", where), "chunks", where);
    const json& dtype = field(j, "dtype", where);
    if (!dtype.is_string()) throwIoError(where, "dtype " + dtype.dump(-1).substr(0, 80) + " is not supported (a structured type)");
    parseDtype(dtype.get<std::string>(), m, where);
    if (j.value("order", std::string("C")) != "C")
        throwIoError(where, "order \"F\" (Fortran) is not supported: only C order");
    if (const auto f = j.find("filters"); f != j.end() && !f->is_null() && !(f->is_array() && f->empty()))
        throwIoError(where, "filters " + f->dump().substr(0, 80) + " are not supported");
    if (const auto c = j.find("compressor"); c != j.end() && !c->is_null()) {
        if (!c->is_object() || !c->contains("id") || !(*c)["id"].is_string())
            throwIoError(where, "compressor has no \"id\"");
        m.compressor = compressorNamed((*c)["id"].get<std::string>(), where);
    }
    m.fill = parseFill(j.value("fill_value", json()), where);
    const std::string separator = j.value("dimension_separator", std::string("."));
    if (separator != "." && separator != "/")
        throwIoError(where, "dimension_separator \"" + separator + "\" is not . or /");
    m.separator = separator[0];
}

// A chunk's codecs: bytes, then at most one of blosc, zstd, gzip.
void parseChunkCodecs(const json& codecs, ZarrArrayMeta& m, const std::string& where) {
    bool sawBytes = false;
    if (!codecs.is_array()) throwIoError(where, "codecs is not a list");
    for (const json& codec : codecs) {
        const std::string name = codec.is_object() ? codec.value("name", std::string()) : "";
        const json config = codec.is_object() ? codec.value("configuration", json::object()) : json::object();
        if (name == "bytes" && !sawBytes) {
            sawBytes = true;
            m.bigEndian = config.is_object() && config.value("endian", std::string("little")) == "big";
        } else if (sawBytes && m.compressor == ZarrCompressor::None &&
                   (name == "blosc" || name == "zstd" || name == "gzip")) {
            m.compressor = compressorNamed(name, where);
        } else if (name == "sharding_indexed") {
            throwIoError(where, "is sharded inside a shard or after other codecs, which is not supported");
        } else {
            throwIoError(where, "codec \"" + name + "\" is not supported here (bytes, then blosc, "
                                "zstd or gzip)");
        }
    }
    if (!sawBytes) throwIoError(where, "has no \"bytes\" codec");
}

void parseV3(const json& j, ZarrArrayMeta& m, const std::string& where) {
    if (j.value("node_type", std::string()) != "array") throwIoError(where, "is not a Zarr array");
    m.shape = integers(field(j, "shape", where), "shape", where);
    const json& dataType = field(j, "data_type", where);
    if (!dataType.is_string()) throwIoError(where, "data_type is not a name");
    parseDataType(dataType.get<std::string>(), m, where);
    const json& grid = field(j, "chunk_grid", where);
    if (!grid.is_object() || grid.value("name", std::string()) != "regular")
        throwIoError(where, "only the regular chunk grid is supported");
    m.chunks = integers(field(field(grid, "configuration", where), "chunk_shape", where), "chunk_shape", where);
    m.keyPrefix = "c";
    m.separator = '/';
    if (const auto k = j.find("chunk_key_encoding"); k != j.end()) {
        const std::string name = k->value("name", std::string("default"));
        if (name == "v2") {
            m.keyPrefix.clear();
            m.separator = '.';
        } else if (name != "default") {
            throwIoError(where, "chunk_key_encoding \"" + name + "\" is not supported");
        }
        if (const auto c = k->find("configuration"); c != k->end() && c->contains("separator")) {
            const std::string s = (*c)["separator"].is_string() ? (*c)["separator"].get<std::string>() : "";
            if (s != "." && s != "/") throwIoError(where, "chunk key separator is not . or /");
            m.separator = s[0];
        }
    }
    m.fill = parseFill(j.value("fill_value", json()), where);
    const json& codecs = field(j, "codecs", where);
    // Sharding: the only codec, holding the chunk codecs of the inner chunks.
    if (codecs.is_array() && !codecs.empty() && codecs[0].is_object() &&
        codecs[0].value("name", std::string()) == "sharding_indexed") {
        if (codecs.size() != 1) throwIoError(where, "has codecs after sharding_indexed, which is not supported");
        const json& config = field(codecs[0], "configuration", where);
        m.shards = m.chunks;
        m.chunks = integers(field(config, "chunk_shape", where), "chunk_shape", where);
        if (m.chunks.size() != m.shards.size())
            throwIoError(where, "its inner chunk_shape and the shard shape differ in length");
        for (size_t a = 0; a < m.chunks.size(); ++a)
            if (m.chunks[a] < 1 || m.shards[a] < m.chunks[a] || m.shards[a] % m.chunks[a] != 0)
                throwIoError(where, "its inner chunks " + chunkShapeText(m.chunks) + " do not divide its shards " +
                                        chunkShapeText(m.shards));
        uint64_t inner = 1;
        for (size_t a = 0; a < m.chunks.size(); ++a)
            if (__builtin_mul_overflow(inner, uint64_t(m.shards[a] / m.chunks[a]), &inner) || inner > (uint64_t(1) << 24))
                throwIoError(where, "its shards hold more than 2^24 inner chunks each");
        const std::string location = config.value("index_location", std::string("end"));
        if (location != "end" && location != "start") throwIoError(where, "index_location \"" + location + "\" is not end or start");
        m.indexAtEnd = location == "end";
        bool indexBytes = false;
        for (const json& codec : field(config, "index_codecs", where)) {
            const std::string name = codec.is_object() ? codec.value("name", std::string()) : "";
            const json c = codec.is_object() ? codec.value("configuration", json::object()) : json::object();
            if (name == "bytes" && !indexBytes && c.is_object() && c.value("endian", std::string("little")) == "little")
                indexBytes = true;
            else if (name == "crc32c" && indexBytes && !m.indexCrc)
                m.indexCrc = true;
            else
                throwIoError(where, "shard index codec \"" + name + "\" is not supported (bytes, little-endian, then crc32c)");
        }
        if (!indexBytes) throwIoError(where, "its shard index has no \"bytes\" codec");
        parseChunkCodecs(field(config, "codecs", where), m, where);
        return;
    }
    parseChunkCodecs(codecs, m, where);
}

}  // namespace

uint64_t ZarrArrayMeta::chunkBytes() const {
    uint64_t n = fileScalarSize(type);
    for (int64_t c : chunks) n = checkedMul(n, uint64_t(c));
    return n;
}

uint64_t ZarrArrayMeta::chunksPerShard() const {
    uint64_t n = 1;
    for (size_t a = 0; a < shards.size(); ++a) n = checkedMul(n, uint64_t(shards[a] / chunks[a]));
    return n;
}

std::string ZarrArrayMeta::chunkKey(const std::vector<int64_t>& index) const {
    std::string key = keyPrefix;
    for (size_t i = 0; i < index.size(); ++i) {
        if (!key.empty()) key += separator;
        key += std::to_string(index[i]);
    }
    return key;
}

ZarrArrayMeta parseZarrArrayMeta(const std::string& text, int format, const std::string& where) {
    json j;
    try {
        j = json::parse(text);
    } catch (const json::exception& e) {
        throwIoError(where, std::string("is not valid JSON: ") + e.what());
    }
    if (!j.is_object()) throwIoError(where, "is not a JSON object");
    ZarrArrayMeta m;
    m.format = format;
    // Compared as JSON, not converted: nlohmann converts a float to int unchecked (3e93 was
    // undefined behaviour, found by fuzz_zarr).
    const auto version = j.find("zarr_format");
    if (version == j.end() || !version->is_number_integer() || *version != format)
        throwIoError(where, "zarr_format is not " + std::to_string(format));
    try {
        if (format == 2)
            parseV2(j, m, where);
        else
            parseV3(j, m, where);
    } catch (const json::exception& e) {
        throwIoError(where, std::string("has a field of the wrong kind: ") + e.what());
    }
    if (m.shape.empty() || m.shape.size() != m.chunks.size())
        throwIoError(where, "shape and chunks differ in length, or are empty");
    // The chunk's byte count saturates instead of wrapping or leaving integers: the shape is
    // the file's word, and may be any size.
    uint64_t bytes = fileScalarSize(m.type);
    for (size_t a = 0; a < m.shape.size(); ++a) {
        if (m.shape[a] < 0 || m.chunks[a] < 1)
            throwIoError(where, "shape " + std::to_string(m.shape[a]) + " or chunk " +
                                    std::to_string(m.chunks[a]) + " is out of range");
        if (__builtin_mul_overflow(bytes, uint64_t(m.chunks[a]), &bytes)) bytes = UINT64_MAX;
    }
    if (bytes > kMaxChunkBytes)
        throwIoError(where, "chunks of " + chunkShapeText(m.chunks) + " samples (" +
                                (bytes == UINT64_MAX ? std::string("over 2^64") : std::to_string(bytes)) +
                                " bytes) are larger than vdiso reads (1 GiB)");
    return m;
}

void decodeZarrChunk(const ZarrArrayMeta& m, const unsigned char* data, size_t size,
                     unsigned char* out, const std::string& where) {
    const size_t want = size_t(m.chunkBytes());
    switch (m.compressor) {
        case ZarrCompressor::None:
            if (size != want)
                throwIoError(where, "holds " + std::to_string(size) + " bytes where an "
                                    "uncompressed chunk has " + std::to_string(want));
            std::copy(data, data + size, out);
            return;
        case ZarrCompressor::Blosc: {
            size_t nbytes = 0;
            if (size > size_t(std::numeric_limits<int>::max()) ||
                blosc_cbuffer_validate(data, size, &nbytes) != 0)
                throwIoError(where, "is not valid blosc data");
            if (nbytes != want)
                throwIoError(where, "decompresses to " + std::to_string(nbytes) + " bytes where a "
                                    "chunk has " + std::to_string(want));
            if (blosc_decompress_ctx(data, out, want, 1) != int(want))
                throwIoError(where, "holds corrupt blosc data");
            return;
        }
        case ZarrCompressor::Zstd: {
            const size_t got = ZSTD_decompress(out, want, data, size);
            if (ZSTD_isError(got))
                throwIoError(where, std::string("holds corrupt zstd data: ") + ZSTD_getErrorName(got));
            if (got != want)
                throwIoError(where, "decompresses to " + std::to_string(got) + " bytes where a "
                                    "chunk has " + std::to_string(want));
            return;
        }
        case ZarrCompressor::Gzip: {
            z_stream z{};
            if (inflateInit2(&z, 15 + 32) != Z_OK) throwIoError(where, "cannot start zlib");
            z.next_in = const_cast<Bytef*>(data);
            z.avail_in = uInt(std::min<size_t>(size, std::numeric_limits<uInt>::max()));
            z.next_out = out;
            z.avail_out = uInt(want);
            const int rc = inflate(&z, Z_FINISH);
            const uint64_t got = z.total_out;
            inflateEnd(&z);
            if (rc != Z_STREAM_END)
                throwIoError(where, rc == Z_BUF_ERROR && got == want
                                        ? "decompresses to more bytes than a chunk has"
                                        : "holds corrupt gzip/zlib data");
            if (got != want)
                throwIoError(where, "decompresses to " + std::to_string(got) + " bytes where a "
                                    "chunk has " + std::to_string(want));
            return;
        }
    }
}

}  // namespace vdiso
