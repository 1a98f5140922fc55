// One object over HTTP(S) or S3, read by byte ranges with libcurl: the store reader's source
// when it is given a URL (io/store/byte_source.h).
//
// Opening sends one ranged GET for the object's first bytes (the store's header), which pins
// its size and version: the ETag, or Last-Modified when the server gives no strong ETag. Every
// later read is a ranged GET sent with If-Match (If-Unmodified-Since), so an object replaced
// while it is read is an error naming it, never a picture mixed from two versions; and the
// answer's Content-Range must be exactly the range asked for, within the size pinned at open.
// s3:// locations are signed with SigV4 by libcurl (io/remote/s3_location.h says where the
// endpoint, region and credentials come from); a request without credentials is anonymous.
//
// Reads are thread-safe and run concurrently, each on an easy handle of its own that shares the
// session's connection cache, all of them run by the session's one transfer thread (HTTP/2
// streams multiplex over one connection where the server offers it; otherwise up to
// RemoteOptions::connections HTTP/1.1 connections are kept alive and reused). A 5xx, a 429,
// a broken or truncated transfer and a request without a byte for the stall timeout are tried
// again, up to RemoteOptions::attempts times with doubling pauses from 100 ms; other 4xx, TLS
// failures and redirect loops are errors at once. With RemoteOptions::diskCacheDir, ranges are
// kept on disk for the pinned version (io/remote/disk_cache.h) and read from there when held (an
// object the open read whole has none: it answers from its head). Errors are IoErrors naming the URL (without
// its query, which may hold a signature) and what the server said.
#pragma once

#include <atomic>
#include <cstdint>
#include <exception>
#include <functional>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "io/error.h"
#include "io/remote/remote_options.h"
#include "io/remote/remote_session.h"

namespace vdiso {

class RangeDiskCache;

// True for http://, https:// and s3:// locations.
bool isRemoteLocation(const std::string& location);

// The location as shown in messages and statistics: without userinfo or query.
std::string displayLocation(const std::string& location);

// A location that does not exist (HTTP 404): Zarr's missing chunks, which are the fill value.
class RemoteNotFound : public IoError {
public:
    using IoError::IoError;
};

struct ByteRange {
    uint64_t offset = 0;
    size_t bytes = 0;
    void* dst = nullptr;
};

// Whether the k-th range of a read arrived intact (the store's checksum of it). With a disk cache,
// a range is kept only once it passes, and a kept range that fails is dropped and fetched again:
// what arrived corrupt once is never served twice. Empty: the range is read unchecked and never
// kept in a disk cache (one kept corrupt would be served on every later run). When it
// is called for a range, its last call is on the bytes the read leaves in dst (a caller may
// keep that answer rather than check again); a read without a disk cache may not call it.
using RangeCheck = std::function<bool(size_t k)>;

class RemoteFile {
public:
    // Throws IoError naming the location when it cannot be reached, is refused, is empty or is
    // served without byte ranges.
    RemoteFile(const std::string& location, const RemoteOptions& options, size_t headBytes);
    // The same, in a session shared with other objects (the connections it keeps are reused).
    // An object that does not exist (404) is a RemoteNotFound.
    RemoteFile(std::shared_ptr<RemoteSession> session, const std::string& location, size_t headBytes);
    ~RemoteFile();
    RemoteFile(const RemoteFile&) = delete;
    RemoteFile& operator=(const RemoteFile&) = delete;

    const std::string& name() const { return mName; }
    uint64_t size() const { return mSize; }
    // The version pinned at open: the ETag as the server sent it, or "Last-Modified: ...".
    const std::string& version() const { return mVersion; }
    // "http", "https" or "s3".
    const char* scheme() const { return mScheme; }

    // Exactly n bytes at `offset` into dst. Throws IoError naming the URL and what is wrong.
    // `intact(0)` checks them (RangeCheck). Once `cancel` (if given) is set, the transfer ends
    // and an IoError saying so is thrown; unlike a failure, it ends no other read.
    void read(uint64_t offset, size_t n, void* dst, const RangeCheck& intact = {},
              const std::atomic<bool>* cancel = nullptr) const;
    // n bytes at `offset` in one GET, of which `pieces` (within dst) are wanted: with a disk
    // cache, each piece is kept and looked up apart, and the GET is sent only when one is missing
    // (or found damaged: `intact(k)` checks piece k).
    void readCovering(uint64_t offset, size_t n, void* dst, std::span<const ByteRange> pieces,
                      const RangeCheck& intact = {}) const;

    // readCovering without waiting, and without a thread held while the request waits: done(error)
    // is called once, with null when dst holds the bytes, on the session's transfer thread (it
    // must be quick), or on this thread before the call returns when no request is needed or the
    // read fails at once. dst, `cancel` and what `intact` looks at must live until then. The same
    // errors as readCovering, as an exception_ptr.
    using ReadDone = std::function<void(std::exception_ptr)>;
    // `alone`: its failure for good does not end the object's other reads (ByteSource's).
    void readCoveringAsync(uint64_t offset, size_t n, void* dst, std::vector<ByteRange> pieces, RangeCheck intact,
                           const std::atomic<bool>* cancel, ReadDone done, bool alone = false) const;
    // Requests worth keeping in flight now (TransferLoop::wantedInFlight: twice what the link
    // carries, over all of the session's objects; `initial` until it can tell), at most `most`.
    size_t wantedInFlight(size_t initial, size_t most) const;
    // Requests the session runs at once at most (RemoteOptions::connections, clamped).
    int connections() const;

    // Requests sent (tries included) and object bytes received by the session.
    uint64_t requests() const;
    uint64_t bytesFetched() const;
    // Requests ended as stragglers and sent again (RemoteSession::stragglerMs).
    uint64_t stragglers() const;
    // Ranges, and their bytes, read from the disk cache instead (0 without one).
    uint64_t diskCacheHits() const;
    uint64_t diskCacheBytes() const;

private:
    struct Answer {
        uint64_t total = 0;  // the object's size, from Content-Range
        size_t bytes = 0;
        std::string etag, lastModified;
    };
    // One ranged GET with its tries, pauses and redirects; `opening` accepts a shorter range (a
    // small object's head) and pins nothing. fetchAsync calls done(answer, null) or (null, error)
    // once, as readCoveringAsync says; fetch waits for it.
    using FetchDone = std::function<void(const Answer*, std::exception_ptr)>;
    Answer fetch(uint64_t offset, size_t n, void* dst, bool opening, const std::atomic<bool>* cancel = nullptr) const;
    void fetchAsync(uint64_t offset, size_t n, void* dst, bool opening, const std::atomic<bool>* cancel,
                    FetchDone done, bool alone = false) const;
    // A fetch's steps on the transfer thread: send a try; judge one that ended (an answer, a
    // failure thrown, or the pause before the next try).
    struct Fetch;
    // readCoveringAsync's answers without a request: from the head kept at the open, or every
    // piece from the disk cache (checked by `intact` as intactPiece says). Throws for a range
    // beyond the object.
    bool answeredHere(uint64_t offset, size_t n, void* dst, const std::vector<ByteRange>& pieces,
                      const RangeCheck& intact, bool whole, size_t count) const;
    // Piece k's check: `intact(k)`; for a range read `whole` (one piece standing for `count`),
    // every one of them.
    static bool intactPiece(const RangeCheck& intact, bool whole, size_t count, size_t k);
    void sendTry(const std::shared_ptr<Fetch>& f) const;
    void tryEnded(const std::shared_ptr<Fetch>& f, CURLcode rc) const;
    bool judgeTry(Fetch& f, CURLcode rc, Answer& answer, int64_t& pauseMs) const;

    struct Impl;
    std::unique_ptr<Impl> mImpl;
    std::string mName;
    const char* mScheme = "http";
    uint64_t mSize = 0;
    std::string mVersion;
    std::vector<unsigned char> mHead;  // the first bytes, kept from the open
    std::unique_ptr<RangeDiskCache> mDiskCache;
};

}  // namespace vdiso
