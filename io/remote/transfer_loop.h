// One thread that runs every transfer of a session (io/remote/remote_session.h) through
// libcurl's multi interface: the sockets of all requests in flight are waited on together, by
// one poll, where curl_easy_perform on each reader's thread made a multi handle, a wake-up pipe
// and a poll loop of its own for every request.
//
// perform(easy) is curl_easy_perform's contract for a caller on any thread: the transfer runs on
// the loop's thread (so do its callbacks: they must be thread-safe towards the caller, which
// waits meanwhile), and the result is returned once the handle has left the loop. The handle is
// the caller's before and after. Progress callbacks are called at least every kTickMs while a
// transfer waits, for cancellation and straggler checks. The loop's thread lives as long as the
// object; no transfer may be running when it goes. In a process forked from the one that made
// it there is no such thread: going there leaves the parent's handles alone.
#pragma once

#include <condition_variable>
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

    // maxConnections: connections the loop keeps open, in use or idle (CURLMOPT_MAXCONNECTS).
    // Throws IoError when libcurl cannot make a multi handle.
    explicit TransferLoop(long maxConnections);
    ~TransferLoop();
    TransferLoop(const TransferLoop&) = delete;
    TransferLoop& operator=(const TransferLoop&) = delete;

    CURLcode perform(CURL* easy);

private:
    struct Pending {
        CURL* easy = nullptr;
        CURLcode result = CURLE_OK;
        bool done = false;
        std::condition_variable finished;
    };
    void run();

    CURLM* mMulti = nullptr;
    pid_t mPid;  // the process whose thread runs the loop
    std::mutex mLock;
    std::vector<Pending*> mSubmitted;  // not yet added to the multi handle
    bool mQuit = false;
    std::thread mThread;
};

}  // namespace vdiso
