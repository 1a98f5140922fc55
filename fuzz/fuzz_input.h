// Support for the fuzz targets (fuzz/README.md): an input as a file the readers can open, with
// no disk involved, and the one place that says which exceptions are an answer.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>

#include "io/readers/helper_process.h"

namespace vdiso::fuzz {

// The bytes as an anonymous in-memory file (memfd), named by a path the readers open like any
// other ("/proc/self/fd/N"); closed with the object.
class MemoryFile {
public:
    MemoryFile(const uint8_t* data, size_t size);
    ~MemoryFile();
    MemoryFile(const MemoryFile&) = delete;
    MemoryFile& operator=(const MemoryFile&) = delete;
    const std::string& path() const { return mPath; }

private:
    int mFd = -1;
    std::string mPath;
};

// Bad input must end in an exception with a message (IoError, std::invalid_argument, ...):
// calls f and lets those through as a normal outcome. std::bad_alloc is a finding (memory sized
// from untrusted numbers), as is every crash, sanitizer report, hang and abort.
//
// A helper process's death (io/readers/helper_process.h) is judged by how it died. An abort (SIGABRT)
// is a third-party library's assertion (GDCM's, on damage only GDCM can see), contained by the
// helper and answered with an error naming the file: accepted here, on purpose. Any other end
// (a crash by another signal, a sanitizer report, libFuzzer's out-of-memory exit, an exit
// without a reply) is a finding, raised here in the fuzzer's own process; the helper has
// usually also left its own artifact, which scripts/fuzz.sh counts as a finding too.
template <class F>
void expectAnswer(F&& f);

}  // namespace vdiso::fuzz

#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <new>

template <class F>
void vdiso::fuzz::expectAnswer(F&& f) {
    try {
        f();
    } catch (const vdiso::HelperDied& e) {
        if (e.signal != SIGABRT) {
            std::fprintf(stderr, "fuzz: a helper process died: %s\n", e.what());
            std::abort();
        }
    } catch (const std::bad_alloc&) {
        std::fprintf(stderr, "fuzz: std::bad_alloc escaped: memory sized from the input\n");
        std::abort();
    } catch (const std::exception& e) {
        if (e.what()[0] == '\0') {
            std::fprintf(stderr, "fuzz: an exception with an empty message\n");
            std::abort();
        }
    }
}
