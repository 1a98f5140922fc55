#include "io/remote/remote_session.h"

#include <algorithm>
#include <condition_variable>
#include <atomic>
#include <cstdlib>
#include <exception>
#include <thread>
#include <vector>
#include <map>
#include <mutex>
#include <new>

#include <unistd.h>

#include "io/error.h"
#include "io/forked_child.h"
#include "io/remote/curl_library.h"
#include "io/remote/transfer_loop.h"

namespace vdiso {

struct RemoteSession::Impl {
    RemoteOptions options;
    CURLSH* share = nullptr;
    std::mutex shareLocks[CURL_LOCK_DATA_LAST];
    mutable std::mutex bucketsLock;
    std::map<std::string, S3Location> buckets;  // resolved once per bucket
    mutable std::mutex firstBytesLock;
    std::vector<double> firstBytesMs;  // the last kFirstBytesKept, as a ring
    size_t firstBytesNext = 0;
    static constexpr size_t kFirstBytesKept = 64;
    std::atomic<int64_t> stragglerMs{0};  // from firstBytesMs, at each new one
    pid_t pid = ::getpid();              // the process whose thread runs the transfers
    std::unique_ptr<TransferLoop> loop;  // last: it ends before the share goes
};

RemoteSession::RemoteSession(const RemoteOptions& options) : mImpl(std::make_unique<Impl>()) {
    curlLibrary();  // loaded and initialised once (io/remote/curl_library.h), or an IoError
    Impl& d = *mImpl;
    d.options = options;
    d.options.connections = std::clamp(options.connections, 1, 256);
    d.options.attempts = std::clamp(options.attempts, 1, 16);
    if (d.options.caFile.empty() && std::getenv("AWS_CA_BUNDLE")) d.options.caFile = std::getenv("AWS_CA_BUNDLE");
    d.share = curlLibrary().share_init();
    if (!d.share) throw std::bad_alloc();
    curlLibrary().share_setopt(d.share, CURLSHOPT_LOCKFUNC,
                      +[](CURL*, curl_lock_data data, curl_lock_access, void* user) {
                          static_cast<Impl*>(user)->shareLocks[data].lock();
                      });
    curlLibrary().share_setopt(d.share, CURLSHOPT_UNLOCKFUNC, +[](CURL*, curl_lock_data data, void* user) {
        static_cast<Impl*>(user)->shareLocks[data].unlock();
    });
    curlLibrary().share_setopt(d.share, CURLSHOPT_USERDATA, &d);
    curlLibrary().share_setopt(d.share, CURLSHOPT_SHARE, CURL_LOCK_DATA_CONNECT);
    curlLibrary().share_setopt(d.share, CURLSHOPT_SHARE, CURL_LOCK_DATA_DNS);
    curlLibrary().share_setopt(d.share, CURLSHOPT_SHARE, CURL_LOCK_DATA_SSL_SESSION);
    // The connection cache keeps the pool's connections, in use or idle: libcurl's default (5)
    // closed the oldest idle one whenever more were open, and with 16-32 requests in flight
    // nearly every request connected anew.
    d.loop = std::make_unique<TransferLoop>(long(d.options.connections), size_t(d.options.connections));
}

RemoteSession::~RemoteSession() {
    mImpl->loop.reset();
    if (mImpl->share) curlLibrary().share_cleanup(mImpl->share);
}

TransferLoop& RemoteSession::loop() { return *mImpl->loop; }

const RemoteOptions& RemoteSession::options() const { return mImpl->options; }

void RemoteSession::noteFirstByteMs(double ms) {
    Impl& d = *mImpl;
    std::lock_guard lock(d.firstBytesLock);
    if (d.firstBytesMs.size() < Impl::kFirstBytesKept) d.firstBytesMs.push_back(ms);
    else d.firstBytesMs[d.firstBytesNext++ % Impl::kFirstBytesKept] = ms;
    if (d.firstBytesMs.size() < kStragglerSamples) return;
    // The deadline made here, once an answer, not at each of the progress calls that ask for it.
    std::vector<double> seen = d.firstBytesMs;
    std::nth_element(seen.begin(), seen.begin() + ptrdiff_t(seen.size() / 2), seen.end());
    d.stragglerMs.store(std::max<int64_t>(kStragglerFloorMs, int64_t(kStragglerFactor * seen[seen.size() / 2])),
                        std::memory_order_relaxed);
}

int64_t RemoteSession::stragglerMs() const { return mImpl->stragglerMs.load(std::memory_order_relaxed); }

S3Location RemoteSession::s3Location(const std::string& s3Url) const {
    std::string bucket, key;
    splitS3Url(s3Url, bucket, key);
    Impl& d = *mImpl;
    {
        std::lock_guard lock(d.bucketsLock);
        if (auto it = d.buckets.find(bucket); it != d.buckets.end()) return withKey(it->second, key);
    }
    S3Location s = resolveS3Location(s3Url, d.options);
    std::lock_guard lock(d.bucketsLock);
    d.buckets.emplace(bucket, s);
    return s;
}

// A fresh easy handle for every transfer, never one used before: libcurl 7.88 (Debian 12) frees
// a transfer's stored headers when the next one starts but keeps a pointer to the last, so a
// reused handle whose next answer begins with a folded header line read freed memory (found by
// fuzz_remote; libcurl 8.0 clears the pointer). Connections, DNS and TLS sessions are reused
// through the share all the same; a handle costs microseconds beside a request.
CURL* RemoteSession::take() {
    Impl& d = *mImpl;
    // A forked child has no transfer thread (and shares the parent's connections): its
    // transfers would wait for ever.
    if (inForkedChild(d.pid))
        throw IoError("a remote store or array opened before fork() cannot be read in the child process: "
                      "open it again there (a pickled vdiso.Store opens itself again)");
    CURL* c = curlLibrary().easy_init();
    if (!c) throw std::bad_alloc();
    curlLibrary().easy_setopt(c, CURLOPT_SHARE, d.share);
    return c;
}

void RemoteSession::give(CURL* c) {
    if (c) curlLibrary().easy_cleanup(c);
}

void RemoteSession::forEach(size_t n, const std::function<void(size_t)>& work) const {
    if (n == 0) return;
    std::atomic<size_t> next{0};
    std::exception_ptr failure;
    std::mutex failureLock;
    auto run = [&] {
        for (size_t i; (i = next.fetch_add(1)) < n;) {
            try {
                work(i);
            } catch (...) {
                std::lock_guard lock(failureLock);
                if (!failure) failure = std::current_exception();
                next = n;
            }
        }
    };
    std::vector<std::thread> threads;
    for (size_t t = 1; t < std::min(n, size_t(mImpl->options.connections)); ++t) threads.emplace_back(run);
    run();
    for (std::thread& t : threads) t.join();
    if (failure) std::rethrow_exception(failure);
}

}  // namespace vdiso
