// One thread that runs every transfer of a session (io/remote/remote_session.h) through
// libcurl's multi interface, driven by sockets (curl_multi_socket_action): one epoll waits on the
// sockets of all requests in flight, a request in flight holds no thread of its own, and libcurl
// is handed only the sockets that are ready. (curl_multi_perform visits every transfer at every
// wake and libcurl 7.88 polls each one's socket on its own: 20 poll calls a request on a view
// of 600 requests, most of them finding nothing.)
//
// submit(easy, done) starts the handle's transfer and returns at once; done(result) is called on
// the loop's thread once the handle has left the loop (the handle is the caller's again), and
// must be quick and not throw: it may submit again or set a timer (after), not wait. The transfers'
// own callbacks run on the loop's thread too. At most `maxInFlight` transfers run at once; the
// others wait their turn in the order they came. Every transfer with a socket is visited at least
// every kTickMs, so its progress callback runs, for cancellation and straggler checks, while it
// waits for an answer.
//
// The loop measures the link as its transfers find it, as BBR does: the bytes it delivers a
// second (the most of the last 64 answers' bytes and of any 16 of them in a row, each over the
// time from their first start to their last end: answers that shared the link and ended
// together count at its rate, and a reader that left the link idle between bursts does not
// lower it),
// the least time to an answer's first byte (the round trip
// without queueing: over the session, so that requests queued behind others do not raise it)
// and the bytes a request brings. wantedInFlight gives twice the delay-bandwidth product in
// requests, plus two: a window too small to fill the link finds the rate it delivers grow
// with it, and so about doubles a round trip; one that fills it settles at twice what the link
// holds, whatever the number of threads reading.
//
// The loop's thread lives as long as the object; no transfer may be running when it goes. In a
// process forked from the one that made it there is no such thread: going there leaves the
// parent's handles alone.
#pragma once

#include <chrono>
#include <condition_variable>
#include <cstddef>
#include <cstdint>
#include <deque>
#include <functional>
#include <memory>
#include <mutex>
#include <thread>
#include <vector>

#include <sys/types.h>

#include <curl/curl.h>

namespace vdiso {

class TransferLoop {
public:
    static constexpr long kTickMs = 100;

    // maxConnections: connections the loop keeps open, in use or idle (CURLMOPT_MAXCONNECTS);
    // maxInFlight: transfers running at once. Throws IoError when libcurl cannot make a multi
    // handle or the system an epoll or event descriptor.
    TransferLoop(long maxConnections, size_t maxInFlight);
    ~TransferLoop();
    TransferLoop(const TransferLoop&) = delete;
    TransferLoop& operator=(const TransferLoop&) = delete;

    using Clock = std::chrono::steady_clock;
    using Done = std::function<void(CURLcode)>;
    // `deadline`: when the transfer must have ended, its time waiting for a turn included; the
    // handle's CURLOPT_TIMEOUT_MS is set to what is left of it when the transfer starts (at
    // least 1 ms: one that waited past it ends at once, timed out). None: the handle's own.
    void submit(CURL* easy, Done done, Clock::time_point deadline = Clock::time_point::max());
    // Calls fn on the loop's thread once `ms` have passed, or at the first tick at which
    // sooner() (if given) says true.
    void after(int64_t ms, std::function<void()> fn, std::function<bool()> sooner = {});

    // Requests worth keeping in flight (see above), at most `most` and at least 2; `initial`
    // (within those) until enough transfers have ended to tell.
    size_t wantedInFlight(size_t initial, size_t most) const;

private:
    struct Pending {
        CURL* easy = nullptr;
        Done done;
        Clock::time_point deadline;
        Clock::time_point started;  // added to the multi handle
    };
    struct Timer {
        Clock::time_point due;
        std::function<void()> fn;
        std::function<bool()> sooner;
    };
    void run();
    void noteEnded(const Pending& p, Clock::time_point now);
    void wake();  // ends the loop's wait (mWakeFd)
    // A fresh epoll of mWakeFd and mSockets, the old one closed (see mStale).
    void renewEpoll();
    // libcurl's asks (CURLMOPT_SOCKETFUNCTION, CURLMOPT_TIMERFUNCTION), on the loop's thread.
    static int onSocket(CURL* easy, curl_socket_t s, int what, void* loop, void* socketData);
    static int onTimer(CURLM* multi, long timeoutMs, void* loop);
    // Hands libcurl a socket's readiness (CURL_CSELECT_* bits, 0: let it look), or its timeout
    // (CURL_SOCKET_TIMEOUT), then ends the transfers that are done; `active` counts those running.
    void act(curl_socket_t s, int bits, size_t& active);

    CURLM* mMulti = nullptr;
    int mEpollFd = -1, mWakeFd = -1;
    // Loop thread only: the sockets libcurl watches with the epoll events it wants, and when it
    // next wants a timeout call.
    struct Watched {
        curl_socket_t socket;
        uint32_t events;
    };
    std::vector<Watched> mSockets;
    Clock::time_point mCurlDue = Clock::time_point::max();
    // The epoll may hold a registration that cannot be removed: libcurl 7.88 closes a socket that
    // never connected before it says REMOVE, and epoll drops a socket only when its last
    // descriptor closes, which a forked child may still hold; ready, it would wake every wait.
    // Set when a REMOVE finds nothing to remove or an event names an unknown socket.
    bool mStale = false;
    pid_t mPid;  // the process whose thread runs the loop
    size_t mMaxInFlight;
    mutable std::mutex mLock;
    std::deque<Pending*> mSubmitted;  // not yet added to the multi handle
    std::vector<Timer> mTimers;       // under mLock
    // The last kEndsKept answers, as a ring: when each ended and its bytes; the least time to a
    // first byte seen. Under mLock.
    static constexpr size_t kEndsKept = 64, kEndsToTell = 16;
    struct End {
        Clock::time_point started, ended;
        double bytes;
    };
    std::vector<End> mEnds;
    size_t mEndsNext = 0;
    double mLeastFirstByte = 0;  // seconds; 0: none yet
    bool mQuit = false;
    std::thread mThread;
};

}  // namespace vdiso
