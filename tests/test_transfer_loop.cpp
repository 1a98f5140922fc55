// io/remote/transfer_loop.h against the kernel's sockets: what the loop's epoll holds after
// libcurl closes a socket that a forked child still holds; a deadline that counts the time a
// transfer waited for its turn.
#include <gtest/gtest.h>

#include <arpa/inet.h>  // htons, ntohs
#include <dirent.h>
#include <fcntl.h>
#include <netinet/in.h>
#include <signal.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <ctime>
#include <fstream>
#include <string>
#include <thread>
#include <vector>

#include "io/remote/curl_library.h"
#include "io/remote/transfer_loop.h"

namespace vdiso {
namespace {

// The registrations of every epoll this process has open ("tfd:" lines of their fdinfo).
int epollRegistrations() {
    int count = 0;
    DIR* dir = ::opendir("/proc/self/fd");
    if (!dir) return -1;
    while (dirent* entry = ::readdir(dir)) {
        const std::string fd = entry->d_name;
        char target[256] = {};
        if (::readlink(("/proc/self/fd/" + fd).c_str(), target, sizeof target - 1) <= 0) continue;
        if (std::string(target) != "anon_inode:[eventpoll]") continue;
        std::ifstream info("/proc/self/fdinfo/" + fd);
        for (std::string line; std::getline(info, line);) count += line.rfind("tfd:", 0) == 0;
    }
    ::closedir(dir);
    return count;
}

double processCpuSeconds() {
    timespec t{};
    ::clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
    return double(t.tv_sec) + double(t.tv_nsec) * 1e-9;
}

size_t discard(char*, size_t size, size_t count, void*) { return size * count; }

// A listening socket on 127.0.0.1 (a port the system chooses) that nobody accepts from.
struct Listener {
    int fd = -1;
    sockaddr_in address{};
    std::string url;  // http://127.0.0.1:PORT/x
};
Listener listenOnLoopback(int backlog, int socketFlags) {
    Listener l;
    l.fd = ::socket(AF_INET, SOCK_STREAM | socketFlags, 0);
    l.address.sin_family = AF_INET;
    l.address.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    socklen_t length = sizeof l.address;
    if (::bind(l.fd, reinterpret_cast<sockaddr*>(&l.address), sizeof l.address) != 0 || ::listen(l.fd, backlog) != 0 ||
        ::getsockname(l.fd, reinterpret_cast<sockaddr*>(&l.address), &length) != 0)
        ADD_FAILURE() << "cannot listen on 127.0.0.1";
    l.url = "http://127.0.0.1:" + std::to_string(ntohs(l.address.sin_port)) + "/x";
    return l;
}

// A GET of `url` whose body is dropped, ending after timeoutMs (connecting: connectTimeoutMs).
CURL* easyGet(const std::string& url, long timeoutMs, long connectTimeoutMs = 0) {
    const CurlLibrary& curl = curlLibrary();
    CURL* easy = curl.easy_init();
    curl.easy_setopt(easy, CURLOPT_URL, url.c_str());
    curl.easy_setopt(easy, CURLOPT_NOSIGNAL, 1L);
    curl.easy_setopt(easy, CURLOPT_WRITEFUNCTION, discard);
    curl.easy_setopt(easy, CURLOPT_TIMEOUT_MS, timeoutMs);
    if (connectTimeoutMs > 0) curl.easy_setopt(easy, CURLOPT_CONNECTTIMEOUT_MS, connectTimeoutMs);
    return easy;
}

// libcurl 7.88 closes a socket that never connected before it tells the loop to stop watching
// it, and epoll drops a socket only when its last descriptor closes: with a forked child holding
// a copy, the registration stayed, and once the child's copy turned ready the loop's every wait
// returned at once (a core spun until the child exited).
TEST(TransferLoop, ASocketClosedWhileAForkedChildHoldsItIsNoLongerWatched) {
    // A listener whose backlog is full, so that the next connect hangs until it is accepted.
    const Listener listening = listenOnLoopback(0, SOCK_NONBLOCK);
    const int listener = listening.fd;
    std::vector<int> filling;
    for (int k = 0; k < 4; ++k) {
        filling.push_back(::socket(AF_INET, SOCK_STREAM | SOCK_NONBLOCK, 0));
        ::connect(filling.back(), reinterpret_cast<const sockaddr*>(&listening.address), sizeof listening.address);
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(200));

    const int before = epollRegistrations();
    TransferLoop loop(4, 4);
    const CurlLibrary& curl = curlLibrary();
    CURL* easy = easyGet(listening.url, 30000, 600);
    std::atomic<bool> done{false};
    CURLcode result = CURLE_OK;
    loop.submit(easy, [&](CURLcode rc) {
        result = rc;
        done = true;
    });
    std::this_thread::sleep_for(std::chrono::milliseconds(200));
    const pid_t child = ::fork();  // holds the connecting socket's descriptor
    if (child == 0) {
        ::sleep(20);
        ::_exit(0);
    }
    ASSERT_GT(child, 0);
    while (!done) std::this_thread::sleep_for(std::chrono::milliseconds(5));
    EXPECT_EQ(result, CURLE_OPERATION_TIMEDOUT);
    curl.easy_cleanup(easy);
    // The pending connects accepted: the child's copy of the closed socket turns ready.
    auto acceptAll = [&] {
        for (int c; (c = ::accept4(listener, nullptr, nullptr, SOCK_NONBLOCK)) >= 0;) ::close(c);
    };
    for (int k = 0; k < 6; ++k) {
        acceptAll();
        std::this_thread::sleep_for(std::chrono::milliseconds(50));
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(250));  // past a tick of the loop

    EXPECT_EQ(epollRegistrations() - before, 1) << "only the loop's wake-up descriptor is left";
    const double cpu0 = processCpuSeconds();
    std::this_thread::sleep_for(std::chrono::milliseconds(500));
    acceptAll();
    EXPECT_LT(processCpuSeconds() - cpu0, 0.2) << "the loop's thread spins on a socket it no longer has";

    ::kill(child, SIGKILL);
    ::waitpid(child, nullptr, 0);
    for (int s : filling) ::close(s);
    ::close(listener);
}

// A transfer's deadline counts from its submission: one that waited its turn behind another (one
// transfer at a time) past its deadline ends, timed out, as soon as it starts, not after the
// whole timeout its handle was given.
TEST(TransferLoop, ADeadlineCountsTheWaitForATurn) {
    // A server that takes connections (the kernel's backlog) and never answers.
    const Listener listening = listenOnLoopback(16, 0);
    const CurlLibrary& curl = curlLibrary();
    using Clock = TransferLoop::Clock;
    struct Ended {
        std::atomic<bool> done{false};
        CURLcode result = CURLE_OK;
        Clock::time_point at;
    } first, second;
    {
        TransferLoop loop(2, 1);
        CURL* a = easyGet(listening.url, 1500);
        CURL* b = easyGet(listening.url, 20000);
        const Clock::time_point start = Clock::now();
        auto note = [](Ended& e) {
            return [&e](CURLcode rc) {
                e.result = rc;
                e.at = Clock::now();
                e.done = true;
            };
        };
        loop.submit(a, note(first));
        loop.submit(b, note(second), start + std::chrono::milliseconds(300));
        while (!first.done || !second.done) std::this_thread::sleep_for(std::chrono::milliseconds(5));
        curl.easy_cleanup(a);
        curl.easy_cleanup(b);
    }
    EXPECT_EQ(first.result, CURLE_OPERATION_TIMEDOUT);
    EXPECT_EQ(second.result, CURLE_OPERATION_TIMEDOUT);
    EXPECT_GE(second.at, first.at) << "the second waited for the first's turn";
    EXPECT_LT(std::chrono::duration<double>(second.at - first.at).count(), 5.0)
        << "the second ran its own 20 s timeout after its deadline had passed";
    ::close(listening.fd);
}

}  // namespace
}  // namespace vdiso
