// The remote byte source (io/remote/remote_file.h) against a server that answers with the
// input: a loopback listener in this process sends the input's first part as the answer to the
// open (the head's ranged GET) and the rest as the answer to one ranged read, then closes.
// Whatever the bytes (statuses, headers, Content-Range, ETag, chunked or short bodies), the
// open and the read either succeed with exactly the bytes asked for or end in an IoError.
// Redirects are not followed here: a Location header must not send the fuzzer elsewhere.
#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cstring>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "fuzz/fuzz_input.h"
#include "io/remote/remote_file.h"

namespace {

std::mutex gLock;
std::vector<std::string> gAnswers;  // one per connection, in turn
size_t gNext = 0;
int gPort = 0;

void serveForever(int listener) {
    for (;;) {
        const int c = ::accept(listener, nullptr, nullptr);
        if (c < 0) continue;
        // The request, up to its blank line (bounded).
        std::string request;
        char buf[1024];
        while (request.find("\r\n\r\n") == std::string::npos && request.size() < 65536) {
            const ssize_t n = ::recv(c, buf, sizeof(buf), 0);
            if (n <= 0) break;
            request.append(buf, size_t(n));
        }
        std::string answer;
        {
            std::lock_guard lock(gLock);
            if (gNext < gAnswers.size()) answer = gAnswers[gNext++];
        }
        for (size_t at = 0; at < answer.size();) {
            const ssize_t n = ::send(c, answer.data() + at, answer.size() - at, MSG_NOSIGNAL);
            if (n <= 0) break;
            at += size_t(n);
        }
        ::close(c);
    }
}

}  // namespace

extern "C" int LLVMFuzzerInitialize(int*, char***) {
    const int listener = ::socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0);
    sockaddr_in a{};
    a.sin_family = AF_INET;
    a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    socklen_t len = sizeof(a);
    if (listener < 0 || ::bind(listener, reinterpret_cast<sockaddr*>(&a), sizeof(a)) != 0 ||
        ::listen(listener, 16) != 0 || ::getsockname(listener, reinterpret_cast<sockaddr*>(&a), &len) != 0)
        std::abort();
    gPort = ntohs(a.sin_port);
    std::thread(serveForever, listener).detach();
    return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    // "<open's answer>\0\0\0\0<the read's answer>"; without the separator the whole input
    // answers the open.
    const std::string input(reinterpret_cast<const char*>(data), size);
    const size_t split = input.find(std::string(4, '\0'));
    {
        std::lock_guard lock(gLock);
        gAnswers = {input.substr(0, split), split == std::string::npos ? std::string() : input.substr(split + 4)};
        gNext = 0;
    }
    vdiso::fuzz::expectAnswer([&] {
        vdiso::RemoteOptions options;
        options.attempts = 1;
        options.connections = 1;
        options.followRedirects = false;
        options.stallTimeoutMs = 1000;
        options.connectTimeoutMs = 1000;
        const vdiso::RemoteFile file("http://127.0.0.1:" + std::to_string(gPort) + "/store.vdiso", options, 64);
        std::vector<unsigned char> bytes(std::min<uint64_t>(file.size(), 4096));
        if (file.size() > 64) file.read(64, size_t(std::min<uint64_t>(file.size() - 64, bytes.size())), bytes.data());
    });
    return 0;
}
