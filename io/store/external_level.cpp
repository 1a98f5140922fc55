#include "io/store/external_level.h"

#include <cstring>
#include <filesystem>
#include <functional>
#include <stdexcept>
#include <nlohmann/json.hpp>

#include "core/brick_levels.h"
#include "io/crc32.h"
#include "io/error.h"
#include "io/remote/remote_file.h"

namespace vdiso {
namespace {

constexpr char kMagic[8] = {'V', 'D', 'I', 'S', 'O', 'E', 'X', 'T'};
constexpr size_t kPinBytes = 12;
constexpr size_t kMaxJsonBytes = 1 << 20;

void put(std::vector<unsigned char>& out, const void* p, size_t n) {
    const auto* b = static_cast<const unsigned char*>(p);
    out.insert(out.end(), b, b + n);
}

template <class T>
T get(const unsigned char* bytes, size_t& at) {
    T v;
    std::memcpy(&v, bytes + at, sizeof v);
    at += sizeof v;
    return v;
}

void encodeLevel(const ExternalLevel& e, std::vector<unsigned char>& out) {
    nlohmann::json j;
    j["kind"] = "zarr";
    j["location"] = e.location;
    j["level"] = e.level;
    j["metadata_crc"] = e.metadataCrc;
    j["chunk_shape"] = {e.chunkShape[0], e.chunkShape[1], e.chunkShape[2]};
    j["chunk_counts"] = {e.chunkCounts[0], e.chunkCounts[1], e.chunkCounts[2]};
    const std::string text = j.dump();
    const uint32_t jsonBytes = uint32_t(text.size());
    put(out, &jsonBytes, 4);
    put(out, text.data(), text.size());
    const uint64_t count = e.pins.size();
    put(out, &count, 8);
    for (const ZarrChunkPin& pin : e.pins) {
        put(out, &pin.bytes, 8);
        put(out, &pin.crc, 4);
    }
}

// One level's description and pins from bytes [at, end); `at` moves past them.
ExternalLevel decodeLevel(const unsigned char* bytes, size_t& at, size_t end, const std::function<void(const std::string&)>& damaged) {
    if (end - at < 12) damaged("a level's description overruns it");
    const uint32_t jsonBytes = get<uint32_t>(bytes, at);
    if (jsonBytes > kMaxJsonBytes || jsonBytes > end - at - 8) damaged("its description overruns it");
    ExternalLevel e;
    try {
        const nlohmann::json j = nlohmann::json::parse(bytes + at, bytes + at + jsonBytes);
        if (j.at("kind").get<std::string>() != "zarr") damaged("kind " + j.at("kind").dump());
        // Integers checked as JSON before conversion: nlohmann converts a float unchecked.
        auto integer = [&](const nlohmann::json& v, int64_t lo, int64_t hi) {
            if (!v.is_number_integer() || v.get<int64_t>() < lo || v.get<int64_t>() > hi) damaged("a field out of range");
            return v.get<int64_t>();
        };
        e.location = j.at("location").get<std::string>();
        e.level = int(integer(j.at("level"), 0, 64));
        e.metadataCrc = uint32_t(integer(j.at("metadata_crc"), 0, 0xffffffffll));
        for (int a = 0; a < 3; ++a) {
            e.chunkShape[a] = integer(j.at("chunk_shape").at(size_t(a)), 1, int64_t(1) << 40);
            e.chunkCounts[a] = integer(j.at("chunk_counts").at(size_t(a)), 1, int64_t(1) << 31);
        }
    } catch (const nlohmann::json::exception& ex) {
        damaged(ex.what());
    }
    at += jsonBytes;
    const uint64_t count = get<uint64_t>(bytes, at);
    // The grid's product, compared without overflow: the record is the file's word.
    const unsigned __int128 expected = (unsigned __int128)e.chunkCounts[0] * uint64_t(e.chunkCounts[1]) *
                                       uint64_t(e.chunkCounts[2]);
    if (expected != count || count > (end - at) / kPinBytes) damaged("its chunk count does not match its chunk grid");
    e.pins.resize(size_t(count));
    for (ZarrChunkPin& pin : e.pins) {
        pin.bytes = get<uint64_t>(bytes, at);
        pin.crc = get<uint32_t>(bytes, at);
    }
    return e;
}

}  // namespace

std::vector<unsigned char> encodeExternalLevels(const std::vector<ExternalLevel>& levels) {
    if (levels.empty()) throw std::logic_error("encodeExternalLevels: no level");
    const bool single = levels.size() == 1;
    const uint32_t version = single ? 1 : 2;
    std::vector<unsigned char> out;
    put(out, kMagic, 8);
    put(out, &version, 4);
    if (!single) {
        const uint32_t count = uint32_t(levels.size());
        put(out, &count, 4);
    }
    for (const ExternalLevel& level : levels) encodeLevel(level, out);
    const uint32_t crc = crc32Of(out.data(), out.size());
    put(out, &crc, 4);
    return out;
}

std::vector<ExternalLevel> decodeExternalLevels(const unsigned char* bytes, size_t n, const std::string& path) {
    const std::function<void(const std::string&)> damaged = [&](const std::string& what) {
        throwIoError(path, "its record of the indexed data is damaged (" + what + ")");
    };
    if (n < 28 || std::memcmp(bytes, kMagic, 8) != 0) damaged("wrong magic");
    uint32_t storedCrc;
    std::memcpy(&storedCrc, bytes + n - 4, 4);
    if (storedCrc != crc32Of(bytes, n - 4)) damaged("checksum mismatch");
    size_t at = 8;
    const uint32_t version = get<uint32_t>(bytes, at);
    if (version != 1 && version != 2) damaged("unknown version " + std::to_string(version));
    const uint32_t count = version == 1 ? 1 : get<uint32_t>(bytes, at);
    if (count < 1 || count > uint32_t(kMaxLevels)) damaged("it lists " + std::to_string(count) + " levels");
    std::vector<ExternalLevel> levels;
    for (uint32_t i = 0; i < count; ++i) {
        levels.push_back(decodeLevel(bytes, at, n - 4, damaged));
    }
    if (at != n - 4) damaged("its chunk count does not match its chunk grid");
    return levels;
}

std::string resolveExternalLocation(const std::string& location, const std::string& indexPath) {
    if (isRemoteLocation(location) || std::filesystem::path(location).is_absolute()) return location;
    if (isRemoteLocation(indexPath)) {
        const std::string base = indexPath.substr(0, indexPath.find('?'));
        return base.substr(0, base.rfind('/') + 1) + location;
    }
    return (std::filesystem::path(indexPath).parent_path() / location).lexically_normal().string();
}

std::string externalLocationFor(const std::string& dataPath, const std::string& indexPath) {
    if (isRemoteLocation(dataPath)) return dataPath.substr(0, dataPath.find('?'));
    const std::filesystem::path data = std::filesystem::absolute(dataPath).lexically_normal();
    if (isRemoteLocation(indexPath)) return data.string();
    const std::filesystem::path folder = std::filesystem::absolute(indexPath).lexically_normal().parent_path();
    std::string relative = data.lexically_relative(folder).string();
    while (relative.size() > 1 && relative.back() == '/') relative.pop_back();
    return relative.empty() ? data.string() : relative;
}

std::string defaultIndexPath(const std::string& dataPath) {
    std::string base = dataPath.substr(0, dataPath.find('?'));
    while (base.size() > 1 && base.back() == '/') base.pop_back();
    return base + ".vdiso";
}

}  // namespace vdiso
