// A local disk cache of one object's fetched ranges (--disk-cache DIR): kept across runs and
// processes, keyed by the object's location and the version pinned at open, bounded in bytes.
//
// Layout: DIR/<hash of the location>/<hash of the version>/<offset>-<bytes>, each entry the
// range's bytes and their CRC-32. An entry is written under a temporary name and renamed into
// place, so another process sees a whole entry or none; an entry of the wrong size or CRC is
// removed and is a miss. Opening an object at another version removes the location's other
// versions. The bound: the cache's total is measured at open and grown by what this process
// writes; past the bound, the least recently used entries (by modification time, which a hit
// refreshes) across the whole cache are removed until it holds 90% of it. Processes sharing
// the folder each keep the bound this way, so it may be passed by what they write between
// their sweeps; an entry another process removed is only a miss.
#pragma once

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <mutex>
#include <string>

namespace vdiso {

class RangeDiskCache {
public:
    // Throws IoError naming the folder when it cannot be made or written.
    RangeDiskCache(const std::string& dir, const std::string& location, const std::string& version,
                   uint64_t maxBytes);

    // The range from the cache into dst; false (a miss) when it holds no whole, intact entry.
    bool read(uint64_t offset, size_t n, void* dst) const;
    // Keeps the range. A failed write (a full disk) is a later miss, not an error. Callers keep
    // only what they verified (RemoteFile's RangeCheck).
    void write(uint64_t offset, size_t n, const void* src) const;
    // Removes the range's entry, found damaged by its reader after read() took it (a hit no more).
    void drop(uint64_t offset, size_t n) const;

    uint64_t hits() const { return mHits.load(); }
    uint64_t hitBytes() const { return mHitBytes.load(); }

private:
    std::string entry(uint64_t offset, size_t n) const;
    void sweep() const;

    std::string mRoot;    // DIR
    std::string mFolder;  // DIR/<location>/<version>
    uint64_t mMaxBytes;
    mutable std::mutex mSweepLock;
    mutable std::atomic<uint64_t> mTotal{0};  // the cache's bytes, as this process knows them
    mutable std::atomic<uint64_t> mHits{0}, mHitBytes{0}, mWrites{0};
};

}  // namespace vdiso
