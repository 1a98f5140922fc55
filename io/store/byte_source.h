// Where a brick store's bytes come from: a local file, or an object over HTTP(S) or S3
// (io/remote/remote_file.h). The store reader (io/store/brick_store.h) reads its header, index and
// bricks through this and nothing else.
#pragma once

#include <atomic>
#include <cstdint>
#include <exception>
#include <functional>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "io/remote/remote_file.h"
#include "io/remote/remote_options.h"

namespace vdiso {

// How a local store is read. Buffered: through the page cache (repeated runs hit memory).
// Cold: the file's pages are dropped at open and every brick is read from the disk, so I/O
// times mean what they say. Cold reads use O_DIRECT (aligned reads of whole 4 KiB blocks; the
// format aligns every brick for it); where the file system refuses O_DIRECT (tmpfs), each
// brick's pages are dropped after it is read instead (posix_fadvise DONTNEED).
enum class ReadMode { Buffered, Cold };

// A read's destination must be aligned to this and have room for the read rounded up to it
// (O_DIRECT reads whole blocks), or be unaligned (the read then goes through the page cache).
constexpr size_t kByteSourceAlignment = 4096;

// The bytes a destination of an n-byte read must have: n rounded up to kByteSourceAlignment, so
// that a buffer the allocator happens to align takes an O_DIRECT read's whole last block.
constexpr size_t roomForRead(size_t n) {
    return (n + kByteSourceAlignment - 1) / kByteSourceAlignment * kByteSourceAlignment;
}

class ByteSource {
public:
    virtual ~ByteSource() = default;
    // The path, or the URL without its query.
    virtual const std::string& name() const = 0;
    virtual uint64_t size() const = 0;
    // Exactly n bytes at `offset` into dst (see kByteSourceAlignment). Throws IoError naming the
    // source, `what` was being read and where. `intact(0)` as for readCovering below.
    virtual void read(uint64_t offset, size_t n, void* dst, const char* what, const RangeCheck& intact = {}) const = 0;
    // n bytes at `offset` into dst, as read() does, in one request; only `pieces` of them (within
    // dst, in order) are wanted, and a remote source's disk cache keeps and finds each apart,
    // so a piece read in one run is found in the next however it is read there. `intact(k)`
    // says whether piece k arrived whole and right (its checksum): a remote source's disk cache
    // keeps only such pieces (io/remote/remote_file.h, RangeCheck); the caller still checks.
    virtual void readCovering(uint64_t offset, size_t n, void* dst, std::span<const ByteRange> pieces,
                              const char* what, const RangeCheck& intact = {}) const {
        (void)pieces;
        (void)intact;
        read(offset, n, dst, what);
    }
    // readCovering without holding this thread while the bytes are on their way: done(error) is
    // called once, with null when dst holds them. A remote source sends the request and returns
    // (RemoteFile::readCoveringAsync: done on its transfer thread, and quick); a local one reads
    // at once and calls done before returning. Once `cancel` (if given) is set, a remote source ends
    // the transfer and done gets the error. dst, `intact`'s targets and `cancel` must live
    // until done.
    // `alone`: a read nothing else waits on (the index's parts read in the background): its
    // failure is its own, where a remote read's failure for good ends the object's other reads
    // (their frame is lost).
    using ReadDone = std::function<void(std::exception_ptr)>;
    virtual void readCoveringAsync(uint64_t offset, size_t n, void* dst, std::vector<ByteRange> pieces,
                                   const char* what, RangeCheck intact, const std::atomic<bool>* cancel,
                                   ReadDone done, bool alone = false) const;
    // Whether readCoveringAsync returns before the bytes come (a remote source).
    virtual bool readsInBackground() const { return false; }
    // "buffered", "direct", "fadvise" (local), "http", "https", "s3" (remote).
    virtual const char* method() const = 0;
    // The bytes read from the file so far (as asked for: not an O_DIRECT read's block padding),
    // or fetched over the network from the URL (the answers' bodies; not what a disk cache
    // gave): the header, the index and the bricks alike. 0 where not counted.
    virtual uint64_t bytesRead() const { return 0; }
    // The remote object behind it, or null for a local file.
    virtual const RemoteFile* remote() const { return nullptr; }
};

// Opens a path or a URL (io/remote/remote_file.h: isRemoteLocation). `headBytes`: what a
// remote source fetches with its open and keeps (the store's header). `mode` is for local files
// (a remote store is always read from the network). Throws IoError naming the location.
std::unique_ptr<ByteSource> openByteSource(const std::string& location, ReadMode mode,
                                           const RemoteOptions& remote, size_t headBytes);

}  // namespace vdiso
