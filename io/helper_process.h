// Helper processes for third-party readers that cannot be trusted with damaged files.
//
// Debian's GDCM asserts (aborts) on damaged DICOM, and libhdf5 1.10 allocates and fills what a
// damaged superblock claims (4 GB for a 1 KB file, found by fuzz_hdf5). Such a library runs in
// a child process forked for the purpose, talking to vdiso over a socket: if it dies, the file
// is refused by name and vdiso goes on; its memory is bounded while it parses a file's
// metadata. io/gdcm_process.h and io/isolated_reader.h are built on this.
#pragma once

#include <sys/types.h>

#include <cstddef>
#include <cstdint>
#include <cstring>
#include <functional>
#include <optional>
#include <stdexcept>
#include <string>
#include <type_traits>

namespace vdiso {

// A child process running `serve(socket)` (which must not return: it ends with _exit), and the
// parent's end of the socket. The child first resets fatal signals to their defaults (vdiso's
// or a fuzzer's handlers must not run there), sends its stderr to /dev/null (libraries print
// before they abort; not under AddressSanitizer, whose reports are kept) and bounds its data
// memory to 1 GiB above its size at the fork (not under AddressSanitizer, whose shadow memory
// the bound would count); liftMemoryBound() removes the bound once the risky parsing is done.
class HelperProcess {
public:
    HelperProcess() = default;
    ~HelperProcess();
    HelperProcess(const HelperProcess&) = delete;
    HelperProcess& operator=(const HelperProcess&) = delete;

    // Forks the child. Throws IoError naming `what` if it cannot.
    void start(const std::string& what, const std::function<void(int socket)>& serve);
    bool running() const { return mChild > 0; }
    int socket() const { return mSocket; }
    // Waits for the child after the socket failed; returns how it ended ("was ended by signal 6
    // (an assertion)", "exited with status 1").
    std::string reap();

private:
    int mSocket = -1;
    pid_t mChild = -1;
};

// In the child: lifts the data memory bound set at the fork.
void liftMemoryBound();

// Whole-buffer socket I/O: false when the peer is gone (never SIGPIPE).
bool sendAll(int fd, const void* data, size_t n);
bool receiveAll(int fd, void* data, size_t n);

// Messages between the processes: fixed-size values and length-prefixed strings in the order
// written (both ends are this program on this machine).
class WireWriter {
public:
    template <class T>
    WireWriter& put(const T& v) {
        static_assert(std::is_trivially_copyable_v<T>);
        mBytes.append(reinterpret_cast<const char*>(&v), sizeof(T));
        return *this;
    }
    WireWriter& put(const std::string& s) {
        put(uint64_t(s.size()));
        mBytes += s;
        return *this;
    }
    template <class T>
    WireWriter& put(const std::optional<T>& v) {
        put(uint8_t(v.has_value()));
        if (v) put(*v);
        return *this;
    }
    const std::string& bytes() const { return mBytes; }

private:
    std::string mBytes;
};

class WireReader {
public:
    explicit WireReader(const std::string& bytes) : mBytes(bytes) {}
    template <class T>
    void get(T& v) {
        static_assert(std::is_trivially_copyable_v<T>);
        need(sizeof(T));
        std::memcpy(&v, mBytes.data() + mAt, sizeof(T));
        mAt += sizeof(T);
    }
    void get(std::string& s) {
        uint64_t n = 0;
        get(n);
        need(n);
        s.assign(mBytes.data() + mAt, size_t(n));
        mAt += size_t(n);
    }
    template <class T>
    void get(std::optional<T>& v) {
        uint8_t has = 0;
        get(has);
        if (!has) return v.reset();
        T x{};
        get(x);
        v = x;
    }

private:
    void need(uint64_t n) const {
        if (n > mBytes.size() - mAt) throw std::runtime_error("helper process: a short message");
    }
    const std::string& mBytes;
    size_t mAt = 0;
};

// A reply: a status byte (0 ok, 1 error message, 2 none), a length and a body.
bool sendReply(int fd, uint8_t status, const std::string& body);
// Receives a reply's status and body (bodies above 4 GiB are refused as a broken helper);
// false when the helper is gone.
bool receiveReply(int fd, uint8_t& status, std::string& body);

}  // namespace vdiso
