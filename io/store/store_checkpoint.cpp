#include "io/store/store_checkpoint.h"

#include <sys/stat.h>

#include <cerrno>
#include <cstring>
#include <fstream>
#include <iterator>

#include "core/brick_levels.h"
#include "io/atomic_output.h"
#include "io/crc32.h"
#include "io/error.h"

namespace vdiso {

namespace {

constexpr char kMagic[8] = {'V', 'D', 'I', 'S', 'O', 'C', 'K', 'P'};
constexpr uint32_t kVersion = 2;  // 2: entries as the store's index holds them

// Appends to the file and to its running CRC.
class CheckpointOut {
public:
    explicit CheckpointOut(const std::string& path) : mFile(path, true) {}
    void bytes(const void* p, size_t n) {
        mFile.append(p, n);
        mCrc = crc32Update(mCrc, p, n);
    }
    template <class T>
    void value(T v) {
        bytes(&v, sizeof v);
    }
    void commit() {
        const uint32_t crc = mCrc;
        mFile.append(&crc, sizeof crc);
        mFile.commit();
    }

private:
    AtomicOutputFile mFile;
    uint32_t mCrc = crc32Of(nullptr, 0);
};

// Reads from the file's bytes; running past their end is damage.
class CheckpointIn {
public:
    CheckpointIn(const std::vector<unsigned char>& bytes, const std::string& path)
        : mBytes(bytes), mPath(path) {}
    const unsigned char* take(uint64_t n) {
        if (n > mBytes.size() - mAt) damaged("ends early");
        const unsigned char* p = mBytes.data() + mAt;
        mAt += size_t(n);
        return p;
    }
    template <class T>
    T value() {
        T v;
        std::memcpy(&v, take(sizeof v), sizeof v);
        return v;
    }
    // A count of items of `itemBytes` each that the bytes left can hold.
    uint64_t count(size_t itemBytes) {
        const uint64_t n = value<uint64_t>();
        if (n > (mBytes.size() - mAt) / itemBytes) damaged("ends early");
        return n;
    }
    [[noreturn]] void damaged(const std::string& what) const {
        throwIoError(mPath,
                     "is a damaged resume checkpoint (" + what + "); run again with --restart");
    }

private:
    const std::vector<unsigned char>& mBytes;
    const std::string& mPath;
    size_t mAt = 0;
};

}  // namespace

void writeStoreCheckpoint(const std::string& path, const StoreCheckpoint& c,
                          const std::vector<CheckpointRing>& rings) {
    CheckpointOut out(path);
    out.bytes(kMagic, sizeof kMagic);
    out.value(kVersion);
    out.value(uint32_t(c.identity.size()));
    out.bytes(c.identity.data(), c.identity.size());
    out.value(c.nextLayer);
    out.value(c.fedSlices);
    out.value(c.fileEnd);
    std::vector<unsigned char> packed(c.entries.size() * store_format::kEntryBytes);
    for (size_t i = 0; i < c.entries.size(); ++i)
        store_format::encodeEntry(c.entries[i], packed.data() + i * store_format::kEntryBytes);
    out.value(uint64_t(c.entries.size()));
    out.bytes(packed.data(), packed.size());
    static_assert(sizeof(SubBlockCode) == 2);
    out.value(uint64_t(c.subBlocks.size()));
    out.bytes(c.subBlocks.data(), c.subBlocks.size() * sizeof(SubBlockCode));
    out.value(uint64_t(c.fineHistogram.size()));
    out.bytes(c.fineHistogram.data(), c.fineHistogram.size() * sizeof(uint64_t));
    out.value(uint32_t(c.levels.size()));
    for (size_t l = 0; l < c.levels.size(); ++l) {
        out.value(c.levels[l].nextSlice);
        out.value(c.levels[l].nextLayer);
        out.value(uint64_t(rings[l].size));
        out.bytes(rings[l].bytes, rings[l].size);
    }
    out.value(uint64_t(c.source.size()));
    out.bytes(c.source.data(), c.source.size());
    out.commit();
}

std::optional<StoreCheckpoint> readStoreCheckpoint(const std::string& path) {
    struct stat st;
    if (::stat(path.c_str(), &st) != 0) {
        if (errno == ENOENT) return std::nullopt;
        throwSystemError(path, "cannot read", errno);
    }
    std::ifstream file(path, std::ios::binary);
    std::vector<unsigned char> bytes((std::istreambuf_iterator<char>(file)),
                                     std::istreambuf_iterator<char>());
    if (!file.good() && !file.eof()) throwIoError(path, "cannot read");
    CheckpointIn in(bytes, path);
    if (bytes.size() < sizeof kMagic + 8 || std::memcmp(bytes.data(), kMagic, sizeof kMagic) != 0)
        in.damaged("not a checkpoint");
    if (crc32Of(bytes.data(), bytes.size() - 4) != [&] {
            uint32_t crc;
            std::memcpy(&crc, bytes.data() + bytes.size() - 4, 4);
            return crc;
        }())
        in.damaged("checksum");
    bytes.resize(bytes.size() - 4);
    in.take(sizeof kMagic);
    if (in.value<uint32_t>() != kVersion) in.damaged("another version");
    StoreCheckpoint c;
    const uint32_t identityBytes = in.value<uint32_t>();
    const unsigned char* identity = in.take(identityBytes);
    c.identity.assign(reinterpret_cast<const char*>(identity), identityBytes);
    c.nextLayer = in.value<int64_t>();
    c.fedSlices = in.value<int64_t>();
    c.fileEnd = in.value<uint64_t>();
    c.entries.resize(size_t(in.count(store_format::kEntryBytes)));
    for (BrickEntry& e : c.entries) {
        uint32_t flags = 0;
        e = store_format::decodeEntry(in.take(store_format::kEntryBytes), flags);
        if (flags > 3) in.damaged("an entry's flags");
    }
    c.subBlocks.resize(size_t(in.count(sizeof(SubBlockCode))));
    std::memcpy(c.subBlocks.data(), in.take(c.subBlocks.size() * sizeof(SubBlockCode)),
                c.subBlocks.size() * sizeof(SubBlockCode));
    c.fineHistogram.resize(size_t(in.count(sizeof(uint64_t))));
    std::memcpy(c.fineHistogram.data(), in.take(c.fineHistogram.size() * 8),
                c.fineHistogram.size() * 8);
    const uint32_t levels = in.value<uint32_t>();
    if (levels >= uint32_t(kMaxLevels)) in.damaged("levels");
    c.levels.resize(levels);
    for (StoreCheckpoint::Level& level : c.levels) {
        level.nextSlice = in.value<int64_t>();
        level.nextLayer = in.value<int64_t>();
        const uint64_t n = in.count(1);
        const unsigned char* ring = in.take(n);
        level.ring.assign(ring, ring + n);
    }
    const uint64_t n = in.count(1);
    const unsigned char* source = in.take(n);
    c.source.assign(source, source + n);
    return c;
}

}  // namespace vdiso
