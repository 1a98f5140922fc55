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
// their sweeps; an entry another process removed is only a miss. A temporary an hour old (its
// writer ended mid-write) is removed when a cache opens.
//
// Entries are written, and the cache swept, by the cache's own thread (started at the first
// write): write() copies the range and returns, so a remote session's transfer thread, which
// keeps what it fetched, never waits on the file system. At most kPendingBytes wait to be
// written; a range beyond that is not kept (a later miss). The destructor writes what waits.
#pragma once

#include <sys/types.h>

#include <atomic>
#include <condition_variable>
#include <cstddef>
#include <cstdint>
#include <deque>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

namespace vdiso {

class RangeDiskCache {
public:
    // Throws IoError naming the folder when it cannot be made or written.
    RangeDiskCache(const std::string& dir, const std::string& location, const std::string& version,
                   uint64_t maxBytes);
    ~RangeDiskCache();
    RangeDiskCache(const RangeDiskCache&) = delete;
    RangeDiskCache& operator=(const RangeDiskCache&) = delete;

    static constexpr size_t kPendingBytes = size_t(64) << 20;

    // The range from the cache into dst; false (a miss) when it holds no whole, intact entry.
    bool read(uint64_t offset, size_t n, void* dst) const;
    // Keeps the range (a copy of it, written by the cache's thread). A failed write (a full
    // disk, no memory for the copy, no thread) is a later miss, not an error: it never throws
    // (it runs on the remote session's transfer thread). Callers keep only what they verified
    // (RemoteFile's RangeCheck).
    void write(uint64_t offset, size_t n, const void* src) const noexcept;
    // Removes the range's entry, found damaged by its reader after read() took it (a hit no more).
    void drop(uint64_t offset, size_t n) const;

    uint64_t hits() const { return mHits.load(); }
    uint64_t hitBytes() const { return mHitBytes.load(); }

private:
    struct Pending {
        uint64_t offset;
        std::vector<unsigned char> bytes;
    };
    std::string entry(uint64_t offset, size_t n) const;
    void writeNow(uint64_t offset, size_t n, const void* src) const;
    void writeWaiting() const;  // the writer thread
    void sweep() const;

    std::string mRoot;    // DIR
    std::string mFolder;  // DIR/<location>/<version>
    uint64_t mMaxBytes;
    mutable std::mutex mSweepLock;
    mutable std::atomic<uint64_t> mTotal{0};  // the cache's bytes, as this process knows them
    mutable std::atomic<uint64_t> mHits{0}, mHitBytes{0}, mWrites{0};
    // Ranges waiting for the writer thread. On the heap: a process forked while the thread
    // waited on `queued` inherits a waiter there that will never leave, and destroying the
    // condition variable would wait for it, so a forked child leaves this block as it is.
    struct Writer {
        std::mutex lock;
        std::condition_variable queued;
        std::deque<Pending> queue;
        size_t queuedBytes = 0;
        bool stopping = false;
        std::thread thread;
    };
    pid_t mPid;  // the process that made the cache (io/forked_child.h)
    std::unique_ptr<Writer> mWriter;
};

}  // namespace vdiso
