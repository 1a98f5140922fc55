#include "io/remote/transfer_loop.h"

#include <algorithm>
#include <cmath>

#include <sys/epoll.h>
#include <sys/eventfd.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

#include "core/thread_name.h"
#include "io/error.h"
#include "io/forked_child.h"
#include "io/remote/curl_library.h"

namespace vdiso {

TransferLoop::TransferLoop(long maxConnections, size_t maxInFlight)
    : mPid(::getpid()), mMaxInFlight(std::max<size_t>(maxInFlight, 1)) {
    const CurlLibrary& curl = curlLibrary();
    mEpollFd = ::epoll_create1(EPOLL_CLOEXEC);
    mWakeFd = ::eventfd(0, EFD_CLOEXEC | EFD_NONBLOCK);
    epoll_event wakeEvent{};
    wakeEvent.events = EPOLLIN;
    wakeEvent.data.fd = mWakeFd;
    if (mEpollFd < 0 || mWakeFd < 0 || ::epoll_ctl(mEpollFd, EPOLL_CTL_ADD, mWakeFd, &wakeEvent) != 0) {
        const std::string why = std::strerror(errno);
        if (mEpollFd >= 0) ::close(mEpollFd);
        if (mWakeFd >= 0) ::close(mWakeFd);
        throw IoError("cannot wait on sockets for remote reads (epoll, eventfd): " + why);
    }
    mMulti = curl.multi_init();
    if (!mMulti) {
        ::close(mEpollFd);
        ::close(mWakeFd);
        throw IoError("libcurl cannot make a multi handle: remote data cannot be read");
    }
    curl.multi_setopt(mMulti, CURLMOPT_MAXCONNECTS, maxConnections);
    curl.multi_setopt(mMulti, CURLMOPT_SOCKETFUNCTION, &TransferLoop::onSocket);
    curl.multi_setopt(mMulti, CURLMOPT_SOCKETDATA, static_cast<void*>(this));
    curl.multi_setopt(mMulti, CURLMOPT_TIMERFUNCTION, &TransferLoop::onTimer);
    curl.multi_setopt(mMulti, CURLMOPT_TIMERDATA, static_cast<void*>(this));
    try {
        mThread = std::thread([this] {
            nameThisThread("vdiso-transfer");
            run();
        });
    } catch (...) {
        curl.multi_cleanup(mMulti);
        ::close(mEpollFd);
        ::close(mWakeFd);
        throw;
    }
}

TransferLoop::~TransferLoop() {
    if (inForkedChild(mPid)) {  // (io/forked_child.h); the multi handle is the parent's too
        abandonThread(mThread);
        ::close(mEpollFd);  // the child's own descriptors: the parent's stay open
        ::close(mWakeFd);
        return;
    }
    {
        std::lock_guard lock(mLock);
        mQuit = true;
    }
    wake();
    mThread.join();
    curlLibrary().multi_cleanup(mMulti);  // may still tell onSocket of sockets closed
    ::close(mEpollFd);
    ::close(mWakeFd);
}

void TransferLoop::wake() {
    const uint64_t one = 1;
    // Fails only when the counter is full, and then the loop is awake already.
    [[maybe_unused]] const ssize_t n = ::write(mWakeFd, &one, sizeof one);
}

int TransferLoop::onSocket(CURL*, curl_socket_t s, int what, void* loop, void*) {
    auto& self = *static_cast<TransferLoop*>(loop);
    auto at = std::find_if(self.mSockets.begin(), self.mSockets.end(), [s](const Watched& w) { return w.socket == s; });
    if (what == CURL_POLL_REMOVE) {
        if (::epoll_ctl(self.mEpollFd, EPOLL_CTL_DEL, s, nullptr) != 0) self.mStale = true;
        if (at != self.mSockets.end()) self.mSockets.erase(at);
        return 0;
    }
    epoll_event e{};
    e.events = ((what & CURL_POLL_IN) ? EPOLLIN : 0u) | ((what & CURL_POLL_OUT) ? EPOLLOUT : 0u);
    e.data.fd = s;
    if (at != self.mSockets.end()) {
        at->events = e.events;
        ::epoll_ctl(self.mEpollFd, EPOLL_CTL_MOD, s, &e);
    } else {
        self.mSockets.push_back({s, e.events});
        // Refused (the user's epoll watches used up): the socket is still looked at every tick.
        ::epoll_ctl(self.mEpollFd, EPOLL_CTL_ADD, s, &e);
    }
    return 0;
}

void TransferLoop::renewEpoll() {
    const int fresh = ::epoll_create1(EPOLL_CLOEXEC);
    if (fresh < 0) return;  // kept as it is; tried again at the next wait
    epoll_event e{};
    e.events = EPOLLIN;
    e.data.fd = mWakeFd;
    ::epoll_ctl(fresh, EPOLL_CTL_ADD, mWakeFd, &e);
    for (const Watched& w : mSockets) {
        e.events = w.events;
        e.data.fd = w.socket;
        ::epoll_ctl(fresh, EPOLL_CTL_ADD, w.socket, &e);
    }
    ::close(mEpollFd);
    mEpollFd = fresh;
    mStale = false;
}

int TransferLoop::onTimer(CURLM*, long timeoutMs, void* loop) {
    auto& self = *static_cast<TransferLoop*>(loop);
    self.mCurlDue = timeoutMs < 0 ? Clock::time_point::max() : Clock::now() + std::chrono::milliseconds(timeoutMs);
    return 0;
}

void TransferLoop::submit(CURL* easy, Done done, Clock::time_point deadline) {
    auto* p = new Pending{easy, std::move(done), deadline, {}};
    std::lock_guard lock(mLock);
    mSubmitted.push_back(p);
    wake();
}

void TransferLoop::after(int64_t ms, std::function<void()> fn, std::function<bool()> sooner) {
    std::lock_guard lock(mLock);
    mTimers.push_back({Clock::now() + std::chrono::milliseconds(std::max<int64_t>(ms, 0)), std::move(fn),
                       std::move(sooner)});
    wake();
}

void TransferLoop::noteEnded(const Pending& p, Clock::time_point now) {
    const CurlLibrary& curl = curlLibrary();
    curl_off_t bytes = 0, firstByteUs = 0;
    curl.easy_getinfo(p.easy, CURLINFO_SIZE_DOWNLOAD_T, &bytes);
    curl.easy_getinfo(p.easy, CURLINFO_STARTTRANSFER_TIME_T, &firstByteUs);
    if (bytes <= 0 || firstByteUs <= 0) return;  // no answer: nothing learnt of the link
    std::lock_guard lock(mLock);
    const double firstByte = double(firstByteUs) * 1e-6;
    mLeastFirstByte = mLeastFirstByte > 0 ? std::min(mLeastFirstByte, firstByte) : firstByte;
    const End end{p.started, now, double(bytes)};
    if (mEnds.size() < kEndsKept) mEnds.push_back(end);
    else mEnds[mEndsNext++ % kEndsKept] = end;
}

size_t TransferLoop::wantedInFlight(size_t initial, size_t most) const {
    constexpr size_t kLeast = 2;
    most = std::max(most, kLeast);
    std::vector<End> ends;
    double leastFirstByte = 0;
    {
        std::lock_guard lock(mLock);
        if (mEnds.size() < kEndsToTell) return std::clamp(initial, kLeast, most);
        ends = mEnds;
        leastFirstByte = mLeastFirstByte;
    }
    // The rate the link delivered: the most over runs of kEndsToTell answers in a row (by when
    // they ended), as BBR keeps its bandwidth's maximum: a reader that did not keep the link
    // busy all the while (a traversal between bursts) did not measure the link.
    std::sort(ends.begin(), ends.end(), [](const End& a, const End& b) { return a.ended < b.ended; });
    double rate = 0, bytes = 0;
    Clock::time_point first = ends.front().started;
    for (const End& e : ends) {
        bytes += e.bytes;
        first = std::min(first, e.started);
    }
    if (const double span = std::chrono::duration<double>(ends.back().ended - first).count(); span > 0)
        rate = bytes / span;  // all of them: answers that shared the link and ended together
    for (size_t k = 0; k + kEndsToTell <= ends.size(); ++k) {
        Clock::time_point runStart = ends[k].started;
        double run = 0;
        for (size_t j = k; j < k + kEndsToTell; ++j) {
            runStart = std::min(runStart, ends[j].started);
            run += ends[j].bytes;
        }
        const double span = std::chrono::duration<double>(ends[k + kEndsToTell - 1].ended - runStart).count();
        if (span > 0) rate = std::max(rate, run / span);
    }
    if (rate <= 0) return most;
    const double perRequest = bytes / double(ends.size());
    const double held = rate * leastFirstByte / perRequest;  // requests the link holds
    return std::clamp(size_t(std::ceil(2 * held)) + 2, kLeast, most);
}

namespace {

// A callback on the loop's thread: one that throws (against its contract) must not end the
// process with std::terminate, nor the loop that runs every other transfer.
template <class Fn>
void call(Fn&& fn) noexcept {
    try {
        fn();
    } catch (...) {
    }
}

}  // namespace

void TransferLoop::act(curl_socket_t s, int bits, size_t& active) {
    const CurlLibrary& curl = curlLibrary();
    int running = 0;
    curl.multi_socket_action(mMulti, s, bits, &running);
    int left = 0;
    while (CURLMsg* message = curl.multi_info_read(mMulti, &left)) {
        if (message->msg != CURLMSG_DONE) continue;
        CURL* easy = message->easy_handle;
        const CURLcode result = message->data.result;  // `message` goes with the removal
        char* user = nullptr;
        curl.easy_getinfo(easy, CURLINFO_PRIVATE, &user);
        curl.multi_remove_handle(mMulti, easy);
        --active;
        auto* p = reinterpret_cast<Pending*>(user);
        noteEnded(*p, Clock::now());
        call([&] { p->done(result); });
        delete p;
    }
}

void TransferLoop::run() {
    const CurlLibrary& curl = curlLibrary();
    std::vector<Pending*> added;
    std::vector<std::function<void()>> due;
    std::vector<curl_socket_t> sockets;
    epoll_event events[64];
    size_t active = 0;
    Clock::time_point nextTick = Clock::now() + std::chrono::milliseconds(kTickMs);
    for (;;) {
        bool quit;
        Clock::time_point now = Clock::now();
        Clock::time_point nextDue = nextTick;
        {
            std::lock_guard lock(mLock);
            while (active + added.size() < mMaxInFlight && !mSubmitted.empty()) {
                added.push_back(mSubmitted.front());
                mSubmitted.pop_front();
            }
            for (size_t k = 0; k < mTimers.size();) {
                if (mTimers[k].due <= now || (mTimers[k].sooner && mTimers[k].sooner())) {
                    due.push_back(std::move(mTimers[k].fn));
                    mTimers[k] = std::move(mTimers.back());
                    mTimers.pop_back();
                } else {
                    nextDue = std::min(nextDue, mTimers[k].due);
                    ++k;
                }
            }
            quit = mQuit;
        }
        for (auto& fn : due) call(fn);
        due.clear();
        for (Pending* p : added) {
            p->started = now;
            curl.easy_setopt(p->easy, CURLOPT_PRIVATE, static_cast<void*>(p));
            if (p->deadline != Clock::time_point::max()) {
                const int64_t leftMs = std::chrono::duration_cast<std::chrono::milliseconds>(p->deadline - now).count();
                curl.easy_setopt(p->easy, CURLOPT_TIMEOUT_MS, long(std::max<int64_t>(leftMs, 1)));
            }
            if (curl.multi_add_handle(mMulti, p->easy) == CURLM_OK) {
                ++active;
            } else {
                call([&] { p->done(CURLE_FAILED_INIT); });
                delete p;
            }
        }
        added.clear();
        if (quit && active == 0) return;
        // libcurl's timeouts (a new transfer's start among them), then every transfer with a
        // socket once a tick: libcurl looks at the socket itself and calls its progress callback.
        if (Clock::now() >= mCurlDue) {
            mCurlDue = Clock::time_point::max();
            act(CURL_SOCKET_TIMEOUT, 0, active);
        }
        if (Clock::now() >= nextTick) {
            sockets.clear();  // act() may change mSockets
            for (const Watched& w : mSockets) sockets.push_back(w.socket);
            for (curl_socket_t s : sockets) act(s, 0, active);
            nextTick = Clock::now() + std::chrono::milliseconds(kTickMs);
            nextDue = std::min(nextDue, nextTick);
        }
        // Until a socket is ready, a submission wakes it, a timer of ours or libcurl's is due, or
        // the tick.
        const Clock::time_point until = std::min(nextDue, mCurlDue);
        const int64_t waitMs = std::clamp<int64_t>(
            std::chrono::duration_cast<std::chrono::milliseconds>(until - Clock::now() + std::chrono::microseconds(999))
                .count(),
            0, kTickMs);
        if (mStale) renewEpoll();
        const int n = ::epoll_wait(mEpollFd, events, int(std::size(events)), int(waitMs));
        for (int k = 0; k < n; ++k) {
            const int fd = events[k].data.fd;
            if (fd == mWakeFd) {
                uint64_t count;
                [[maybe_unused]] const ssize_t got = ::read(mWakeFd, &count, sizeof count);
                continue;
            }
            if (std::none_of(mSockets.begin(), mSockets.end(), [fd](const Watched& w) { return w.socket == fd; })) {
                mStale = true;  // a registration left from a socket libcurl closed
                continue;
            }
            const uint32_t e = events[k].events;
            act(fd,
                ((e & EPOLLIN) ? CURL_CSELECT_IN : 0) | ((e & EPOLLOUT) ? CURL_CSELECT_OUT : 0) |
                    ((e & (EPOLLERR | EPOLLHUP)) ? CURL_CSELECT_ERR : 0),
                active);
        }
    }
}

}  // namespace vdiso
