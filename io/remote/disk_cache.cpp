#include "io/remote/disk_cache.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <vector>

#include "core/thread_name.h"
#include "io/crc32.h"
#include "io/error.h"
#include "io/forked_child.h"

namespace vdiso {

namespace fs = std::filesystem;

namespace {

// 64-bit FNV-1a, as 16 hex digits: a folder name that is the same in every build and process.
std::string hashName(const std::string& text) {
    uint64_t h = 1469598103934665603ull;
    for (const unsigned char c : text) h = (h ^ c) * 1099511628211ull;
    char out[17];
    std::snprintf(out, sizeof(out), "%016llx", (unsigned long long)h);
    return out;
}

bool isEntryName(const std::string& name) {
    return !name.empty() && name[0] != '.' && name.find('-') != std::string::npos;
}

// A temporary this old was left by a process that ended while writing it (a write takes
// milliseconds): removed when a cache opens, or it would be neither counted nor swept.
constexpr auto kStaleTemporary = std::chrono::hours(1);

// Every entry under `root` (not the temporaries being written), with its size and time; with
// `removeStale`, the stale temporaries go.
struct Entry {
    fs::path path;
    uint64_t bytes;
    fs::file_time_type time;
};
std::vector<Entry> listEntries(const fs::path& root, bool removeStale = false) {
    std::vector<Entry> entries, stale;
    const fs::file_time_type now = fs::file_time_type::clock::now();
    std::error_code ec;
    for (fs::recursive_directory_iterator it(root, ec), end; !ec && it != end; it.increment(ec)) {
        if (!it->is_regular_file(ec)) continue;
        const std::string name = it->path().filename().string();
        const fs::file_time_type time = it->last_write_time(ec);
        if (!isEntryName(name)) {
            if (removeStale && !ec && name.starts_with(".tmp-") && now - time > kStaleTemporary)
                stale.push_back({it->path(), 0, time});
            ec.clear();
            continue;
        }
        const uint64_t bytes = it->file_size(ec);
        if (!ec) entries.push_back({it->path(), bytes, time});
        ec.clear();
    }
    for (const Entry& e : stale) fs::remove(e.path, ec);
    return entries;
}

}  // namespace

RangeDiskCache::RangeDiskCache(const std::string& dir, const std::string& location,
                               const std::string& version, uint64_t maxBytes)
    : mRoot(dir), mMaxBytes(maxBytes), mPid(::getpid()), mWriter(std::make_unique<Writer>()) {
    const fs::path objectFolder = fs::path(dir) / hashName(location);
    const std::string versionName = hashName(version);
    mFolder = (objectFolder / versionName).string();
    std::error_code ec;
    fs::create_directories(mFolder, ec);
    if (ec) throwIoError(dir, "cannot be made a disk cache: " + ec.message());
    if (::access(mFolder.c_str(), W_OK) != 0) throwSystemError(dir, "cannot be written as a disk cache", errno);
    // The object changed: what was cached of its other versions goes.
    for (fs::directory_iterator it(objectFolder, ec), end; !ec && it != end; it.increment(ec))
        if (it->path().filename() != versionName) fs::remove_all(it->path(), ec);
    uint64_t total = 0;
    for (const Entry& e : listEntries(mRoot, true)) total += e.bytes;
    mTotal = total;
    if (total > mMaxBytes) sweep();
}

std::string RangeDiskCache::entry(uint64_t offset, size_t n) const {
    return mFolder + "/" + std::to_string(offset) + "-" + std::to_string(n);
}

bool RangeDiskCache::read(uint64_t offset, size_t n, void* dst) const {
    const std::string path = entry(offset, n);
    const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
    if (fd < 0) return false;
    bool whole = false;
    struct stat st {};
    uint32_t crc = 0;
    if (::fstat(fd, &st) == 0 && uint64_t(st.st_size) == uint64_t(n) + sizeof(crc)) {
        size_t done = 0;
        auto* p = static_cast<char*>(dst);
        while (done < n) {
            const ssize_t r = ::pread(fd, p + done, n - done, off_t(done));
            if (r < 0 && errno == EINTR) continue;
            if (r <= 0) break;
            done += size_t(r);
        }
        whole = done == n && ::pread(fd, &crc, sizeof(crc), off_t(n)) == ssize_t(sizeof(crc)) &&
                crc == crc32Of(dst, n);
    }
    if (whole) ::futimens(fd, nullptr);  // recently used
    ::close(fd);
    if (!whole) {
        ::unlink(path.c_str());
        return false;
    }
    ++mHits;
    mHitBytes += n;
    return true;
}

RangeDiskCache::~RangeDiskCache() {
    if (inForkedChild(mPid)) {  // (mWriter's note in the header)
        if (mWriter->thread.joinable()) abandonThread(mWriter->thread);
        mWriter.release();
        return;
    }
    {
        std::lock_guard lock(mWriter->lock);
        mWriter->stopping = true;
    }
    mWriter->queued.notify_one();
    if (mWriter->thread.joinable()) mWriter->thread.join();
}

void RangeDiskCache::write(uint64_t offset, size_t n, const void* src) const noexcept {
    if (inForkedChild(mPid) || n > kPendingBytes) return;
    Writer& w = *mWriter;
    try {
        const auto* p = static_cast<const unsigned char*>(src);
        Pending range{offset, std::vector<unsigned char>(p, p + n)};  // copied outside the lock
        {
            std::lock_guard lock(w.lock);
            if (w.stopping || w.queuedBytes + n > kPendingBytes) return;
            if (!w.thread.joinable()) w.thread = std::thread([this] { writeWaiting(); });
            w.queue.push_back(std::move(range));
            w.queuedBytes += n;
        }
        w.queued.notify_one();
    } catch (...) {  // no memory for the copy, or no thread: not kept
    }
}

void RangeDiskCache::writeWaiting() const {
    nameThisThread("vdiso-cache");
    Writer& w = *mWriter;
    std::unique_lock lock(w.lock);
    for (;;) {
        w.queued.wait(lock, [&] { return w.stopping || !w.queue.empty(); });
        if (w.queue.empty()) return;  // stopping, and nothing left to write
        Pending next = std::move(w.queue.front());
        w.queue.pop_front();
        lock.unlock();
        try {
            writeNow(next.offset, next.bytes.size(), next.bytes.data());
        } catch (...) {  // (a file system that fails a sweep's listing): a later miss
        }
        lock.lock();
        w.queuedBytes -= next.bytes.size();
    }
}

void RangeDiskCache::writeNow(uint64_t offset, size_t n, const void* src) const {
    const std::string path = entry(offset, n);
    const std::string temporary = mFolder + "/.tmp-" + std::to_string(::getpid()) + "-" +
                                  std::to_string(mWrites.fetch_add(1));
    const int fd = ::open(temporary.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0644);
    if (fd < 0) return;
    const uint32_t crc = crc32Of(src, n);
    bool written = true;
    for (const auto& [data, bytes] : {std::pair{static_cast<const char*>(src), n},
                                      std::pair{reinterpret_cast<const char*>(&crc), sizeof(crc)}}) {
        for (size_t done = 0; written && done < bytes;) {
            const ssize_t w = ::write(fd, data + done, bytes - done);
            if (w < 0 && errno == EINTR) continue;
            if (w <= 0) written = false;
            else done += size_t(w);
        }
    }
    written = ::close(fd) == 0 && written;
    if (!written || ::rename(temporary.c_str(), path.c_str()) != 0) {
        ::unlink(temporary.c_str());
        return;
    }
    if ((mTotal += n + sizeof(crc)) > mMaxBytes) sweep();
}

void RangeDiskCache::drop(uint64_t offset, size_t n) const {
    if (::unlink(entry(offset, n).c_str()) == 0) mTotal -= std::min<uint64_t>(mTotal, n + sizeof(uint32_t));
    --mHits;
    mHitBytes -= n;
}

void RangeDiskCache::sweep() const {
    std::unique_lock lock(mSweepLock, std::try_to_lock);
    if (!lock) return;  // another thread is sweeping
    std::vector<Entry> entries = listEntries(mRoot);
    std::sort(entries.begin(), entries.end(), [](const Entry& a, const Entry& b) { return a.time < b.time; });
    uint64_t total = 0;
    for (const Entry& e : entries) total += e.bytes;
    const uint64_t target = mMaxBytes / 10 * 9;
    std::error_code ec;
    for (const Entry& e : entries) {
        if (total <= target) break;
        if (fs::remove(e.path, ec)) total -= e.bytes;
    }
    mTotal = total;
}

}  // namespace vdiso
