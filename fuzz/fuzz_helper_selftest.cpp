// The fuzz gate's self-test (scripts/fuzz.sh selftest): a helper process (io/readers/helper_process.h)
// that ends as the input's first byte says, so the gate can be shown to fail on every way a
// helper can die in a campaign, and to accept the one answer it accepts on purpose:
//   'H' a heap-buffer-overflow (an AddressSanitizer report in the helper)
//   'S' a segmentation fault
//   'M' an allocation past libFuzzer's -malloc_limit_mb (its out-of-memory exit)
//   'X' an exit without a reply
//   'A' an abort, as a library's assertion: contained, answered with an error, not a finding
// Any other input gets a reply and is not a finding. Not a fuzz target: fuzz.sh runs it on
// single inputs only.
#include <unistd.h>

#include <csignal>
#include <cstdlib>
#include <cstring>
#include <string>

#include "fuzz/fuzz_input.h"
#include "io/readers/helper_process.h"
#include "io/readers/helper_wire.h"

namespace {

[[gnu::noinline]] void overflowHeap() {
    volatile char* block = static_cast<char*>(std::malloc(16));
    block[16 + (reinterpret_cast<uintptr_t>(block) & 1)] = 1;
    std::free(const_cast<char*>(block));
}

void serveOne(int fd) {
    char kind = 0;
    if (!vdiso::receiveAll(fd, &kind, 1)) ::_exit(0);
    switch (kind) {
        case 'H': overflowHeap(); break;
        case 'S': std::raise(SIGSEGV); break;
        case 'M': {
            void* volatile huge = std::malloc(size_t(8) << 30);
            std::memset(huge, 1, 4096);
            break;
        }
        case 'X': ::_exit(3);
        case 'A': std::abort();
    }
    vdiso::sendReply(fd, 0, "fine");
    ::_exit(0);
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    if (size == 0) return 0;
    vdiso::fuzz::expectAnswer([&] {
        vdiso::HelperProcess helper;
        helper.start("self-test input", serveOne);
        const char kind = char(data[0]);
        uint8_t status = 0;
        std::string body;
        if (!vdiso::sendAll(helper.socket(), &kind, 1) ||
            !vdiso::receiveReply(helper.socket(), status, body))
            helper.died("self-test input", "the self-test helper", "answering", "as asked");
    });
    return 0;
}
