// What the objects read from one place share: libcurl's connection cache, DNS and TLS sessions
// (so a second object reuses the first one's connection), the thread that runs their transfers
// (io/remote/transfer_loop.h), the bound of RemoteOptions::connections requests in flight, and
// the counts of requests and bytes.
// A store's one object (io/remote/remote_file.h) has a session of its own; the chunks of a Zarr
// array over HTTP or S3 (io/readers/zarr_keys.h) share one.
#pragma once

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <memory>

#include <curl/curl.h>

#include "io/remote/remote_options.h"
#include "io/remote/s3_location.h"
#include "io/remote/transfer_loop.h"

namespace vdiso {

class RemoteSession {
public:
    // The options clamped to what they may be (1-256 connections, 1-16 attempts) and AWS_CA_BUNDLE
    // applied. Throws IoError when libcurl cannot be initialised.
    explicit RemoteSession(const RemoteOptions& options);
    ~RemoteSession();
    RemoteSession(const RemoteSession&) = delete;
    RemoteSession& operator=(const RemoteSession&) = delete;

    const RemoteOptions& options() const;

    // A new easy handle set to share the session's caches; give it back (it is cleaned up) when
    // its one transfer ends. Throws IoError in a process forked from the one that made the
    // session.
    CURL* take();
    void give(CURL* curl);
    // The session's one thread of transfers (io/remote/transfer_loop.h), where the sockets of
    // every request in flight are waited on together, at most `connections` transfers at once
    // (the others wait their turn): submit, timers, and the requests worth keeping in
    // flight.
    TransferLoop& loop();

    // Calls work(i) for i in [0, n), on up to `connections` threads at once (this one among
    // them): each call waits on the network, not a core. The first exception ends the rest
    // (those not started are not) and is thrown once all have returned.
    void forEach(size_t n, const std::function<void(size_t)>& work) const;

    // An s3:// location resolved (io/remote/s3_location.h): the first object of a bucket reads
    // the environment and AWS's files, the others reuse what it found. Thread-safe.
    S3Location s3Location(const std::string& s3Url) const;

    // Requests sent (tries included) and object bytes received by every object of the session;
    // requests given up as stragglers and sent again (stragglerMs).
    std::atomic<uint64_t> requests{0}, bytesFetched{0}, stragglers{0};

    // Answers' first bytes: each request's time to them is noted, and a request that has had
    // none for kStragglerFactor times their median (at least kStragglerFloorMs, and only once
    // kStragglerSamples were noted) is a straggler, tried again at once rather than waited for
    // until the stall timeout: an object store's slowest answers take many times its usual ones.
    // 0: no straggler deadline yet. Thread-safe.
    static constexpr int64_t kStragglerFactor = 8, kStragglerFloorMs = 1000;
    static constexpr size_t kStragglerSamples = 8;
    void noteFirstByteMs(double ms);
    int64_t stragglerMs() const;

private:
    struct Impl;
    std::unique_ptr<Impl> mImpl;
};

}  // namespace vdiso
