#include "io/remote/remote_file.h"

#include <algorithm>
#include <cstring>
#include <exception>

#include "io/error.h"
#include "io/remote/disk_cache.h"
#include "io/remote/http_answer.h"
#include "io/remote/remote_file_impl.h"

namespace vdiso {

bool isRemoteLocation(const std::string& location) {
    return location.rfind("http://", 0) == 0 || location.rfind("https://", 0) == 0 ||
           location.rfind("s3://", 0) == 0;
}

std::string displayLocation(const std::string& location) {
    std::string shown = location.substr(0, location.find_first_of("?#"));
    const size_t scheme = shown.find("://");
    if (scheme != std::string::npos) {
        const size_t hostEnd = shown.find('/', scheme + 3);
        const size_t at = shown.rfind('@', hostEnd);
        if (at != std::string::npos && at > scheme) shown.erase(scheme + 3, at - scheme - 2);
    }
    return shown;
}

namespace {

// A session for reading `location`, libcurl loaded first so that a failure to load it names the
// location.
std::shared_ptr<RemoteSession> sessionFor(const std::string& location, const RemoteOptions& options) {
    curlLibraryFor(displayLocation(location));
    return std::make_shared<RemoteSession>(options);
}

}  // namespace

RemoteFile::RemoteFile(const std::string& location, const RemoteOptions& options, size_t headBytes)
    : RemoteFile(sessionFor(location, options), location, headBytes) {}

RemoteFile::RemoteFile(std::shared_ptr<RemoteSession> session, const std::string& location,
                       size_t headBytes)
    : mImpl(std::make_unique<Impl>()), mName(displayLocation(location)) {
    Impl& d = *mImpl;
    d.session = std::move(session);
    if (location.rfind("s3://", 0) == 0) {
        d.s3 = d.session->s3Location(location);
        d.url = d.s3->url;
        mScheme = "s3";
        if (!d.s3->accessKey.empty()) {
            d.sigv4 = "aws:amz:" + d.s3->region + ":s3";
            d.userPassword = d.s3->accessKey + ":" + d.s3->secretKey;
            // S3 wants the payload's hash in a header of its own; a GET has none to sign.
            d.headers = curlLibrary().slist_append(d.headers, "x-amz-content-sha256: UNSIGNED-PAYLOAD");
            if (!d.s3->sessionToken.empty())
                d.headers = curlLibrary().slist_append(d.headers, ("x-amz-security-token: " + d.s3->sessionToken).c_str());
        }
    } else {
        d.url = location;
        mScheme = location.rfind("https://", 0) == 0 ? "https" : "http";
    }
    bool hasUser = false;
    http_answer::originOf(d.url, &hasUser);
    d.credentialed = !d.sigv4.empty() || hasUser;

    // The head: its Content-Range gives the size, its ETag the version every later read pins.
    mHead.resize(std::max<size_t>(headBytes, 1));
    const Answer head = fetch(0, mHead.size(), mHead.data(), true);
    mSize = head.total;
    mHead.resize(head.bytes);
    if (head.etag.size() > 2 && head.etag.rfind("W/", 0) != 0) {
        mVersion = head.etag;
        d.condition = "If-Match: " + head.etag;
        d.pinnedEtag = head.etag;
    } else if (!head.lastModified.empty()) {
        mVersion = "Last-Modified: " + head.lastModified;
        d.condition = "If-Unmodified-Since: " + head.lastModified;
        d.pinnedLastModified = head.lastModified;
    }
    const RemoteOptions& options = d.session->options();
    // An object the open read whole (a Zarr's chunks and metadata) answers every read from its
    // head: no disk cache, whose opening measures the cache's folder (with 30,000 entries kept,
    // an indexed Zarr's view spent 12 s of system time opening one a chunk).
    if (!options.diskCacheDir.empty() && mHead.size() < mSize) {
        if (mVersion.empty())
            throwIoError(mName, "is served without an ETag or Last-Modified: with no version to "
                                "key them by, its ranges cannot be kept in a disk cache");
        mDiskCache = std::make_unique<RangeDiskCache>(options.diskCacheDir, displayLocation(d.url), mVersion,
                                                      options.diskCacheBytes);
    }
}

RemoteFile::~RemoteFile() = default;

uint64_t RemoteFile::requests() const { return mImpl->session->requests.load(); }
uint64_t RemoteFile::bytesFetched() const { return mImpl->session->bytesFetched.load(); }
uint64_t RemoteFile::stragglers() const { return mImpl->session->stragglers.load(); }
uint64_t RemoteFile::diskCacheHits() const { return mDiskCache ? mDiskCache->hits() : 0; }
uint64_t RemoteFile::diskCacheBytes() const { return mDiskCache ? mDiskCache->hitBytes() : 0; }

void RemoteFile::read(uint64_t offset, size_t n, void* dst, const RangeCheck& intact,
                      const std::atomic<bool>* cancel) const {
    DoneLatch latch;
    readCoveringAsync(offset, n, dst, {}, intact ? RangeCheck([&](size_t) { return intact(0); }) : RangeCheck(), cancel,
                      latch.signal());
    latch.wait();
}

void RemoteFile::readCovering(uint64_t offset, size_t n, void* dst, std::span<const ByteRange> pieces,
                              const RangeCheck& intact) const {
    DoneLatch latch;
    readCoveringAsync(offset, n, dst, std::vector<ByteRange>(pieces.begin(), pieces.end()), intact, nullptr,
                      latch.signal());
    latch.wait();
}

void RemoteFile::readCoveringAsync(uint64_t offset, size_t n, void* dst, std::vector<ByteRange> pieces,
                                   RangeCheck intact, const std::atomic<bool>* cancel, ReadDone done,
                                   bool alone) const {
    // `done` is called once, and never from inside the try: a callback that threw would
    // otherwise be called again from the catch.
    std::exception_ptr failure;
    try {
        // Without pieces, or for the store's head (kept from the open), the range is one piece.
        const bool whole = pieces.size() < 2 || offset < mHead.size();
        const size_t count = std::max<size_t>(pieces.size(), 1);
        if (whole) pieces.assign(1, ByteRange{offset, n, dst});
        if (n == 0 || answeredHere(offset, n, dst, pieces, intact, whole, count)) {
            done(nullptr);
            return;
        }
        fetchAsync(offset, n, dst, false, cancel, [this, pieces, intact, whole, count, done](const Answer*, std::exception_ptr e) {
            // Only what a check passed is kept: a range read unchecked could be kept corrupt.
            if (!e && mDiskCache && intact)
                for (size_t k = 0; k < pieces.size(); ++k)
                    if (intactPiece(intact, whole, count, k)) mDiskCache->write(pieces[k].offset, pieces[k].bytes, pieces[k].dst);
            done(e);
        }, alone);
        return;
    } catch (...) {
        failure = std::current_exception();
    }
    done(failure);
}

bool RemoteFile::intactPiece(const RangeCheck& intact, bool whole, size_t count, size_t k) {
    if (!intact) return true;
    if (!whole) return intact(k);
    for (size_t j = 0; j < count; ++j)  // the whole range: intact when each piece is
        if (!intact(j)) return false;
    return true;
}

bool RemoteFile::answeredHere(uint64_t offset, size_t n, void* dst, const std::vector<ByteRange>& pieces,
                              const RangeCheck& intact, bool whole, size_t count) const {
    if (offset > mSize || n > mSize - offset)
        throwIoError(mName, "has " + std::to_string(mSize) + " bytes: no range " + std::to_string(offset) + "-" +
                                std::to_string(offset + n - 1));
    if (offset + n <= mHead.size()) {
        std::memcpy(dst, mHead.data() + offset, n);
        intactPiece(intact, whole, count, 0);  // its last call is on what dst holds (RangeCheck)
        return true;
    }
    if (!mDiskCache) return false;
    for (size_t k = 0; k < pieces.size(); ++k) {
        if (!mDiskCache->read(pieces[k].offset, pieces[k].bytes, pieces[k].dst)) return false;
        if (!intactPiece(intact, whole, count, k)) {
            mDiskCache->drop(pieces[k].offset, pieces[k].bytes);  // kept damaged: fetched anew
            return false;
        }
    }
    return true;
}

size_t RemoteFile::wantedInFlight(size_t initial, size_t most) const {
    return mImpl->session->loop().wantedInFlight(initial, most);
}


int RemoteFile::connections() const { return mImpl->session->options().connections; }

}  // namespace vdiso
