#include "io/dicom_decoder.h"

#include <gdcmImage.h>
#include <gdcmImageReader.h>
#include <gdcmTransferSyntax.h>

#include <sys/socket.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <csignal>
#include <cstring>
#include <vector>

#include "io/error.h"

namespace vdiso {
namespace {

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

// In the helper: decodes one file's pixel data into `samples`; returns "" or what is wrong.
std::string decodeHere(const DicomPixelRequest& r, std::vector<char>& samples) {
    gdcm::ImageReader reader;
    reader.SetFileName(r.path.c_str());
    if (!reader.Read()) return "cannot be read as a DICOM image (transfer syntax " + r.transferSyntax + ")";
    const gdcm::Image& image = reader.GetImage();
    const gdcm::PixelFormat& format = image.GetPixelFormat();
    if (image.GetDimension(0) != r.columns || image.GetDimension(1) != r.rows ||
        (image.GetNumberOfDimensions() > 2 && image.GetDimension(2) != 1) ||
        format.GetSamplesPerPixel() != 1 || format.GetBitsAllocated() != r.bitsAllocated)
        return "its pixel data is not the " + std::to_string(r.columns) + " x " +
               std::to_string(r.rows) + " single-channel " + std::to_string(r.bitsAllocated) +
               "-bit image its header describes";
    const size_t bytes = size_t(r.rows) * r.columns * (r.bitsAllocated / 8);
    if (image.GetBufferLength() != bytes)
        return "its pixel data is " + std::to_string(image.GetBufferLength()) + " bytes where " +
               std::to_string(bytes) + " are needed";
    samples.resize(bytes);
    if (!image.GetBuffer(samples.data())) {
        const char* name = image.GetTransferSyntax().GetString();
        return "its pixel data (transfer syntax " + r.transferSyntax + ", " +
               (name ? name : "unknown") + ") cannot be decoded by this GDCM, or is damaged";
    }
    return "";
}

// The helper's loop: a request is the path, the transfer syntax and three numbers; the reply a
// status, a message and, on success, the samples. Ends when the socket closes.
[[noreturn]] void serve(int fd) {
    std::vector<char> samples;
    for (;;) {
        uint32_t head[5];  // path length, syntax length, rows, columns, bits allocated
        if (!receiveAll(fd, head, sizeof(head))) ::_exit(0);
        DicomPixelRequest r;
        r.path.resize(head[0]);
        r.transferSyntax.resize(head[1]);
        if (!receiveAll(fd, r.path.data(), head[0]) ||
            !receiveAll(fd, r.transferSyntax.data(), head[1]))
            ::_exit(0);
        r.rows = head[2];
        r.columns = head[3];
        r.bitsAllocated = head[4];
        std::string error;
        try {
            error = decodeHere(r, samples);
        } catch (const std::exception& e) {
            error = std::string("cannot be decoded: ") + e.what();
        }
        const uint64_t reply[2] = {error.empty() ? 0u : 1u, error.size()};
        if (!sendAll(fd, reply, sizeof(reply)) || !sendAll(fd, error.data(), error.size()) ||
            (error.empty() && !sendAll(fd, samples.data(), samples.size())))
            ::_exit(0);
    }
}

}  // namespace

DicomPixelDecoder::~DicomPixelDecoder() { stop(); }

void DicomPixelDecoder::start() {
    int fds[2];
    if (::socketpair(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0, fds) != 0)
        throwSystemError("DICOM decoder", "cannot create its socket", errno);
    const pid_t pid = ::fork();
    if (pid < 0) {
        const int e = errno;
        ::close(fds[0]);
        ::close(fds[1]);
        throwSystemError("DICOM decoder", "cannot start its process", e);
    }
    if (pid == 0) {
        ::close(fds[0]);
        serve(fds[1]);
    }
    ::close(fds[1]);
    mSocket = fds[0];
    mChild = pid;
}

void DicomPixelDecoder::stop() {
    if (mSocket >= 0) ::close(mSocket);  // the helper sees the end and exits
    mSocket = -1;
    if (mChild > 0) {
        int status = 0;
        while (::waitpid(mChild, &status, 0) < 0 && errno == EINTR) {
        }
    }
    mChild = -1;
}

void DicomPixelDecoder::decode(const DicomPixelRequest& r, void* dst) {
    if (mChild < 0) start();
    const uint32_t head[5] = {uint32_t(r.path.size()), uint32_t(r.transferSyntax.size()), r.rows,
                              r.columns, r.bitsAllocated};
    uint64_t reply[2] = {0, 0};
    const bool talked = sendAll(mSocket, head, sizeof(head)) &&
                        sendAll(mSocket, r.path.data(), r.path.size()) &&
                        sendAll(mSocket, r.transferSyntax.data(), r.transferSyntax.size()) &&
                        receiveAll(mSocket, reply, sizeof(reply)) && reply[1] < (1u << 20);
    std::string error(talked ? size_t(reply[1]) : 0, '\0');
    if (talked && receiveAll(mSocket, error.data(), error.size())) {
        if (reply[0] != 0) throwIoError(r.path, error);
        const size_t bytes = size_t(r.rows) * r.columns * (r.bitsAllocated / 8);
        if (receiveAll(mSocket, dst, bytes)) return;
    }
    // The helper died: GDCM aborted (an assertion) or crashed on this file.
    ::close(mSocket);
    mSocket = -1;
    int status = 0;
    while (::waitpid(mChild, &status, 0) < 0 && errno == EINTR) {
    }
    mChild = -1;
    const std::string how = WIFSIGNALED(status)
                                ? "was ended by signal " + std::to_string(WTERMSIG(status)) +
                                      (WTERMSIG(status) == SIGABRT ? " (an assertion)" : "")
                                : "exited";
    throwIoError(r.path, "GDCM " + how + " decoding its pixel data (transfer syntax " +
                             r.transferSyntax + "): it is damaged or in a form GDCM cannot handle");
}

}  // namespace vdiso
