// RemoteFile's state (io/remote/remote_file.h), shared by its two sources: remote_file.cpp (the
// object: its open and its reads by ranges) and remote_fetch.cpp (one ranged GET with its tries).
// Internal to io/remote.
#pragma once

#include <atomic>
#include <condition_variable>
#include <cstdint>
#include <exception>
#include <functional>
#include <memory>
#include <mutex>
#include <optional>
#include <string>

#include <curl/curl.h>

#include "io/remote/curl_library.h"
#include "io/remote/remote_file.h"
#include "io/remote/remote_session.h"
#include "io/remote/s3_location.h"

namespace vdiso {

struct RemoteFile::Impl {
    std::shared_ptr<RemoteSession> session;
    std::string url;  // what is requested: the location, or an s3:// location's http(s) URL
    std::optional<S3Location> s3;
    std::string sigv4, userPassword;
    curl_slist* headers = nullptr;  // fixed headers: S3's payload hash and session token
    std::string condition;          // "If-Match: ..." or "If-Unmodified-Since: ...", once pinned
    std::string pinnedEtag, pinnedLastModified;  // what every answer must still say
    bool credentialed = false;      // signed, or a URL with userinfo: redirects stay at its origin
    std::atomic<uint64_t> failures{0};  // reads that failed for good
    std::mutex failureLock;
    std::string failure;  // the last one's message, which the reads it ended repeat

    // Where a read starts: `url`, or where a permanent redirect (301, 308) of it led, once an
    // answer came from there (RFC 9110 15.4.2: the new URI is to be used for future requests;
    // a temporary one, 302 or 307, is followed again at every read).
    std::string where() const {
        std::lock_guard lock(movedLock);
        return movedTo.empty() ? url : movedTo;
    }
    void moveTo(const std::string& to) {
        std::lock_guard lock(movedLock);
        movedTo = to;
    }
    mutable std::mutex movedLock;
    std::string movedTo;

    ~Impl() { curlLibrary().slist_free_all(headers); }
};

// Waits for one asynchronous call's done(error), on the calling thread.
class DoneLatch {
public:
    std::function<void(std::exception_ptr)> signal() {
        return [this](std::exception_ptr e) {
            // Under the lock, so that the waiter (whose stack holds this) cannot return first.
            std::lock_guard lock(mLock);
            mError = e;
            mDone = true;
            mChanged.notify_one();
        };
    }
    void wait() {
        std::unique_lock lock(mLock);
        mChanged.wait(lock, [&] { return mDone; });
        if (mError) std::rethrow_exception(mError);
    }

private:
    std::mutex mLock;
    std::condition_variable mChanged;
    bool mDone = false;
    std::exception_ptr mError;
};

}  // namespace vdiso
