// The messages between vdiso and its helper processes (io/readers/helper_process.h): whole-buffer
// socket I/O and a simple encoding. Apart from helper_process.cpp so that the run-time modules
// that serve a helper's requests themselves (io/readers/gdcm_module/gdcm_module.h) can build it in
// without the rest of vdiso_io: it needs nothing but libc.
#pragma once

#include <cstddef>
#include <cstdint>
#include <cstring>
#include <optional>
#include <stdexcept>
#include <string>
#include <type_traits>

namespace vdiso {

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
