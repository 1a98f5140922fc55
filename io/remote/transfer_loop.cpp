#include "io/remote/transfer_loop.h"

#include <unistd.h>

#include "io/error.h"
#include "io/forked_child.h"
#include "io/remote/curl_library.h"

namespace vdiso {

TransferLoop::TransferLoop(long maxConnections) : mPid(::getpid()) {
    const CurlLibrary& curl = curlLibrary();
    mMulti = curl.multi_init();
    if (!mMulti) throw IoError("libcurl cannot make a multi handle: remote data cannot be read");
    curl.multi_setopt(mMulti, CURLMOPT_MAXCONNECTS, maxConnections);
    mThread = std::thread([this] { run(); });
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

CURLcode TransferLoop::perform(CURL* easy) {
    Pending pending;
    pending.easy = easy;
    std::unique_lock lock(mLock);
    mSubmitted.push_back(&pending);
    curlLibrary().multi_wakeup(mMulti);
    pending.finished.wait(lock, [&] { return pending.done; });
    return pending.result;
}

void TransferLoop::run() {
    const CurlLibrary& curl = curlLibrary();
    // Under the lock, so that the waiter (whose stack holds `p`) cannot return before the call.
    auto finish = [&](Pending* p, CURLcode result) {
        std::lock_guard lock(mLock);
        p->result = result;
        p->done = true;
        p->finished.notify_one();
    };
    std::vector<Pending*> added;
    size_t active = 0;
    for (;;) {
        bool quit;
        {
            std::lock_guard lock(mLock);
            added.swap(mSubmitted);
            quit = mQuit;
        }
        for (Pending* p : added) {
            curl.easy_setopt(p->easy, CURLOPT_PRIVATE, static_cast<void*>(p));
            if (curl.multi_add_handle(mMulti, p->easy) == CURLM_OK) ++active;
            else finish(p, CURLE_FAILED_INIT);
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
            finish(reinterpret_cast<Pending*>(user), result);
        }
        // Until a socket is ready, a submission wakes it, or the tick (libcurl's own timers
        // shorten it).
        curl.multi_poll(mMulti, nullptr, 0, int(kTickMs), nullptr);
    }
}

}  // namespace vdiso
