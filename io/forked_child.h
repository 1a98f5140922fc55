// Objects that own threads, met in a process forked from the one that made them (Python's
// multiprocessing forks its workers): the child has none of those threads, and joining or
// detaching one there touches the parent's thread records that fork reclaimed (a crash).
// Such an object notes the process it was made in and, going in another, gives up its
// threads' handles without a call into the thread library.
#pragma once

#include <thread>
#include <utility>

#include <sys/types.h>
#include <unistd.h>

namespace vdiso {

// Whether this process is not `owner` (getpid() at construction): a forked child.
inline bool inForkedChild(pid_t owner) { return ::getpid() != owner; }

// Leaves `t` not joinable without joining or detaching it: its handle is moved into an object
// that is never destroyed (a few bytes, once a fork).
inline void abandonThread(std::thread& t) { new std::thread(std::move(t)); }

}  // namespace vdiso
