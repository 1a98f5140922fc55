#include "io/readers/helper_process.h"

#include <fcntl.h>
#include <sys/resource.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <csignal>
#include <cstdlib>
#include <fstream>

#include "io/error.h"

#if defined(__SANITIZE_ADDRESS__)
#define VDISO_HELPER_HAS_ASAN 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define VDISO_HELPER_HAS_ASAN 1
#endif
#endif
#ifndef VDISO_HELPER_HAS_ASAN
#define VDISO_HELPER_HAS_ASAN 0
#endif

namespace vdiso {
namespace {

#if !VDISO_HELPER_HAS_ASAN  // under ASan the helper keeps the parent's bounds (prepareChild)
constexpr uint64_t kMetadataMemory = uint64_t(1) << 30;

// The process's data memory now, from /proc/self/status (VmData, in kB); 0 if unknown.
uint64_t dataBytes() {
    std::ifstream status("/proc/self/status");
    std::string line;
    while (std::getline(status, line))
        if (line.rfind("VmData:", 0) == 0) return std::strtoull(line.c_str() + 7, nullptr, 10) * 1024;
    return 0;
}
#endif

void prepareChild() {
    for (int sig : {SIGABRT, SIGSEGV, SIGBUS, SIGILL, SIGFPE}) std::signal(sig, SIG_DFL);
#if !VDISO_HELPER_HAS_ASAN
    const int devNull = ::open("/dev/null", O_WRONLY | O_CLOEXEC);
    if (devNull >= 0) ::dup2(devNull, STDERR_FILENO);
    if (const uint64_t have = dataBytes(); have > 0) {
        rlimit limit{};
        ::getrlimit(RLIMIT_DATA, &limit);
        limit.rlim_cur = rlim_t(have + kMetadataMemory);
        if (limit.rlim_max != RLIM_INFINITY && limit.rlim_cur > limit.rlim_max)
            limit.rlim_cur = limit.rlim_max;
        ::setrlimit(RLIMIT_DATA, &limit);
    }
#endif
}

}  // namespace

void liftMemoryBound() {
    rlimit limit{};
    if (::getrlimit(RLIMIT_DATA, &limit) != 0) return;
    limit.rlim_cur = limit.rlim_max;
    ::setrlimit(RLIMIT_DATA, &limit);
}

HelperProcess::~HelperProcess() {
    if (mSocket >= 0) ::close(mSocket);  // the helper sees the end and exits
    if (mChild > 0) {
        int status = 0;
        while (::waitpid(mChild, &status, 0) < 0 && errno == EINTR) {
        }
    }
}

void HelperProcess::start(const std::string& what, const std::function<void(int)>& serve) {
    int fds[2];
    if (::socketpair(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0, fds) != 0)
        throwSystemError(what, "cannot create a socket for its helper process", errno);
    const pid_t pid = ::fork();
    if (pid < 0) {
        const int e = errno;
        ::close(fds[0]);
        ::close(fds[1]);
        throwSystemError(what, "cannot start its helper process", e);
    }
    if (pid == 0) {
        ::close(fds[0]);
        prepareChild();
        serve(fds[1]);
        ::_exit(0);
    }
    ::close(fds[1]);
    mSocket = fds[0];
    mChild = pid;
}

void HelperProcess::died(const std::string& what, const std::string& library,
                         const std::string& doing, const std::string& advice) {
    if (mSocket >= 0) ::close(mSocket);
    mSocket = -1;
    int status = 0;
    while (mChild > 0 && ::waitpid(mChild, &status, 0) < 0 && errno == EINTR) {
    }
    mChild = -1;
    const int signal = WIFSIGNALED(status) ? WTERMSIG(status) : 0;
    const int exitStatus = WIFEXITED(status) ? WEXITSTATUS(status) : 0;
    const std::string how = signal ? "was ended by signal " + std::to_string(signal) +
                                         (signal == SIGABRT ? " (an assertion)" : "")
                                   : "exited with status " + std::to_string(exitStatus);
    throw HelperDied(what + ": " + library + " " + how + " " + doing + ": " + advice, signal,
                     exitStatus);
}

}  // namespace vdiso
