#include "io/remote/transfer_loop.h"

#include <algorithm>
#include <cmath>

#include <unistd.h>

#include "core/thread_name.h"
#include "io/error.h"
#include "io/forked_child.h"
#include "io/remote/curl_library.h"

namespace vdiso {

TransferLoop::TransferLoop(long maxConnections, size_t maxInFlight)
    : mPid(::getpid()), mMaxInFlight(std::max<size_t>(maxInFlight, 1)) {
    const CurlLibrary& curl = curlLibrary();
    mMulti = curl.multi_init();
    if (!mMulti) throw IoError("libcurl cannot make a multi handle: remote data cannot be read");
    curl.multi_setopt(mMulti, CURLMOPT_MAXCONNECTS, maxConnections);
    mThread = std::thread([this] {
        nameThisThread("vdiso-transfer");
        run();
    });
}

TransferLoop::~TransferLoop() {
    if (inForkedChild(mPid)) {  // (io/forked_child.h); the multi handle is the parent's too
        abandonThread(mThread);
        return;
    }
    {
        std::lock_guard lock(mLock);
        mQuit = true;
        curlLibrary().multi_wakeup(mMulti);
    }
    mThread.join();
    curlLibrary().multi_cleanup(mMulti);
}

void TransferLoop::submit(CURL* easy, Done done) {
    auto* p = new Pending{easy, std::move(done), {}};
    std::lock_guard lock(mLock);
    mSubmitted.push_back(p);
    curlLibrary().multi_wakeup(mMulti);
}

void TransferLoop::after(int64_t ms, std::function<void()> fn, std::function<bool()> sooner) {
    std::lock_guard lock(mLock);
    mTimers.push_back({Clock::now() + std::chrono::milliseconds(std::max<int64_t>(ms, 0)), std::move(fn),
                       std::move(sooner)});
    curlLibrary().multi_wakeup(mMulti);
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

void TransferLoop::run() {
    const CurlLibrary& curl = curlLibrary();
    std::vector<Pending*> added;
    std::vector<std::function<void()>> due;
    size_t active = 0;
    for (;;) {
        bool quit;
        Clock::time_point now = Clock::now();
        Clock::time_point nextDue = now + std::chrono::milliseconds(kTickMs);
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
            if (curl.multi_add_handle(mMulti, p->easy) == CURLM_OK) {
                ++active;
            } else {
                call([&] { p->done(CURLE_FAILED_INIT); });
                delete p;
            }
        }
        added.clear();
        if (quit && active == 0) return;
        int running = 0;
        curl.multi_perform(mMulti, &running);
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
        // Until a socket is ready, a submission wakes it, a timer is due or the tick (libcurl's
        // own timers shorten it).
        const auto waitMs = std::chrono::duration_cast<std::chrono::milliseconds>(nextDue - Clock::now()).count();
        curl.multi_poll(mMulti, nullptr, 0, int(std::clamp<int64_t>(waitMs, 0, kTickMs)), nullptr);
    }
}

}  // namespace vdiso
