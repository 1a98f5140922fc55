// A process-wide request to stop, for Ctrl-C and SIGTERM: the CLI's signal handler calls
// requestInterrupt() (a lock-free atomic store, safe in a handler); every long loop in the
// libraries (reading, skipping, converting, extracting) calls throwIfInterrupted() often
// enough to stop within a second: every few MB read or skipped, every brick or slab.
// The exception unwinds like any other error, so partial output is removed.
#pragma once

#include <atomic>
#include <stdexcept>
#include <string>

namespace vdiso {

// Thrown by throwIfInterrupted(): "<where>: interrupted".
class Interrupted : public std::runtime_error {
public:
    using std::runtime_error::runtime_error;
};

namespace detail {
inline std::atomic<bool> gInterruptRequested{false};
static_assert(std::atomic<bool>::is_always_lock_free);
}  // namespace detail

inline void requestInterrupt() { detail::gInterruptRequested.store(true, std::memory_order_relaxed); }
inline void clearInterrupt() { detail::gInterruptRequested.store(false, std::memory_order_relaxed); }
inline bool interruptRequested() { return detail::gInterruptRequested.load(std::memory_order_relaxed); }

// Throws Interrupted("<where>: interrupted") if an interrupt was requested; `where` names the
// file or operation, as every message does.
inline void throwIfInterrupted(const std::string& where) {
    if (interruptRequested()) throw Interrupted(where + ": interrupted");
}

}  // namespace vdiso
