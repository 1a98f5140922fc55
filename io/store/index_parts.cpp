#include "io/store/index_parts.h"

#include <tbb/parallel_for.h>
#include <zstd.h>

#include <algorithm>
#include <atomic>
#include <cstring>

#include "io/crc32.h"
#include "io/error.h"
#include "io/store/store_format.h"

namespace vdiso::store_format {

namespace {

constexpr char kPackedMagic[8] = {'V', 'D', 'I', 'S', 'O', 'I', 'X', 'Z'};
constexpr size_t kDirectoryHead = 24;  // magic, raw bytes, part bytes, part count
constexpr int kIndexZstdLevel = 3;

uint64_t partCount(uint64_t rawBytes) { return (rawBytes + kIndexPartBytes - 1) / kIndexPartBytes; }
uint64_t directoryBytes(uint64_t parts) { return kDirectoryHead + 8 * parts + 4; }

template <class T>
T load(const unsigned char* p) {
    T v;
    std::memcpy(&v, p, sizeof v);
    return v;
}

}  // namespace

uint64_t packedIndexMin(uint64_t rawBytes) { return directoryBytes(partCount(rawBytes)); }

uint64_t packedIndexMax(uint64_t rawBytes) {
    const uint64_t parts = partCount(rawBytes);
    return directoryBytes(parts) + parts * ZSTD_compressBound(kIndexPartBytes);
}

std::vector<unsigned char> packIndex(const std::vector<unsigned char>& raw) {
    const size_t parts = size_t(partCount(raw.size()));
    std::vector<std::vector<unsigned char>> packed(parts);
    tbb::parallel_for(size_t(0), parts, [&](size_t i) {
        const size_t at = i * kIndexPartBytes, n = std::min<size_t>(kIndexPartBytes, raw.size() - at);
        packed[i].resize(ZSTD_compressBound(n));
        const size_t r = ZSTD_compress(packed[i].data(), packed[i].size(), raw.data() + at, n, kIndexZstdLevel);
        if (ZSTD_isError(r)) throw IoError(std::string("cannot compress the index: ") + ZSTD_getErrorName(r));
        packed[i].resize(r);
    });
    std::vector<unsigned char> out(directoryBytes(parts));
    unsigned char* p = out.data();
    std::memcpy(p, kPackedMagic, 8);
    const uint64_t rawBytes = raw.size();
    std::memcpy(p + 8, &rawBytes, 8);
    const uint32_t partBytes = kIndexPartBytes, count = uint32_t(parts);
    std::memcpy(p + 16, &partBytes, 4);
    std::memcpy(p + 20, &count, 4);
    for (size_t i = 0; i < parts; ++i) {
        const uint32_t size = uint32_t(packed[i].size()), crc = crc32Of(packed[i].data(), packed[i].size());
        std::memcpy(p + kDirectoryHead + 8 * i, &size, 4);
        std::memcpy(p + kDirectoryHead + 8 * i + 4, &crc, 4);
    }
    const uint32_t directoryCrc = crc32Of(p, out.size() - 4);
    std::memcpy(p + out.size() - 4, &directoryCrc, 4);
    for (const auto& part : packed) out.insert(out.end(), part.begin(), part.end());
    return out;
}

size_t IndexDirectory::rawBytesOf(uint64_t i) const {
    return size_t(std::min<uint64_t>(kIndexPartBytes, rawBytes - i * kIndexPartBytes));
}

uint64_t indexDirectoryBytes(uint64_t rawBytes) { return directoryBytes(partCount(rawBytes)); }

IndexDirectory decodeIndexDirectory(const unsigned char* stored, uint64_t storedBytes, uint64_t rawBytes,
                                    const std::string& path) {
    const uint64_t parts = partCount(rawBytes);
    const uint64_t directory = directoryBytes(parts);
    if (storedBytes < directory || std::memcmp(stored, kPackedMagic, 8) != 0)
        throwIoError(path, "index is missing or corrupt (wrong magic)");
    if (load<uint64_t>(stored + 8) != rawBytes || load<uint32_t>(stored + 16) != kIndexPartBytes ||
        load<uint32_t>(stored + 20) != parts)
        throwIoError(path, "index directory does not match the header's bricks");
    if (load<uint32_t>(stored + directory - 4) != crc32Of(stored, size_t(directory) - 4))
        throwIoError(path, "index directory checksum mismatch (the index is corrupt)");
    IndexDirectory d;
    d.rawBytes = rawBytes;
    d.offsets.assign(size_t(parts) + 1, directory);
    d.crcs.resize(size_t(parts));
    for (uint64_t i = 0; i < parts; ++i) {
        d.offsets[i + 1] = d.offsets[i] + load<uint32_t>(stored + kDirectoryHead + 8 * i);
        d.crcs[i] = load<uint32_t>(stored + kDirectoryHead + 8 * i + 4);
    }
    if (d.offsets.back() != storedBytes)
        throwIoError(path, "index parts hold " + std::to_string(d.offsets.back()) + " bytes where the header says " +
                               std::to_string(storedBytes));
    return d;
}

bool unpackIndexPart(const IndexDirectory& d, uint64_t i, const unsigned char* stored, unsigned char* raw) {
    const size_t size = size_t(d.offsets[i + 1] - d.offsets[i]), want = d.rawBytesOf(i);
    return d.crcs[i] == crc32Of(stored, size) && ZSTD_decompress(raw, want, stored, size) == want;
}

std::unique_ptr<unsigned char[]> unpackIndex(const unsigned char* stored, size_t n, uint64_t rawBytes,
                                             const std::string& path) {
    const IndexDirectory d = decodeIndexDirectory(stored, n, rawBytes, path);
    auto raw = std::make_unique_for_overwrite<unsigned char[]>(size_t(rawBytes));
    std::atomic<int64_t> badPart{-1};
    tbb::parallel_for(uint64_t(0), d.parts(), [&](uint64_t i) {
        if (!unpackIndexPart(d, i, stored + d.offsets[i], raw.get() + i * kIndexPartBytes)) {
            int64_t none = -1;
            badPart.compare_exchange_strong(none, int64_t(i));
        }
    });
    if (badPart >= 0)
        throwIoError(path, "index part " + std::to_string(badPart.load()) + " of " + std::to_string(d.parts()) +
                               " is corrupt (checksum mismatch or bad zstd data)");
    return raw;
}

}  // namespace vdiso::store_format
