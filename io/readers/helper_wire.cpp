#include "io/readers/helper_wire.h"

#include <sys/socket.h>

#include <cerrno>

namespace vdiso {

bool sendAll(int fd, const void* data, size_t n) {
    const auto* p = static_cast<const char*>(data);
    while (n > 0) {
        const ssize_t sent = ::send(fd, p, n, MSG_NOSIGNAL);  // a dead peer: an error, no SIGPIPE
        if (sent < 0 && errno == EINTR) continue;
        if (sent <= 0) return false;
        p += sent;
        n -= size_t(sent);
    }
    return true;
}

bool receiveAll(int fd, void* data, size_t n) {
    auto* p = static_cast<char*>(data);
    while (n > 0) {
        const ssize_t got = ::recv(fd, p, n, 0);
        if (got < 0 && errno == EINTR) continue;
        if (got <= 0) return false;
        p += got;
        n -= size_t(got);
    }
    return true;
}

bool sendReply(int fd, uint8_t status, const std::string& body) {
    const uint64_t size = body.size();
    return sendAll(fd, &status, 1) && sendAll(fd, &size, sizeof(size)) &&
           sendAll(fd, body.data(), body.size());
}

bool receiveReply(int fd, uint8_t& status, std::string& body) {
    uint64_t size = 0;
    if (!receiveAll(fd, &status, 1) || !receiveAll(fd, &size, sizeof(size)) ||
        size > (uint64_t(1) << 32))
        return false;
    body.resize(size_t(size));
    return receiveAll(fd, body.data(), body.size());
}

}  // namespace vdiso
