// Helper processes for third-party readers that cannot be trusted with damaged files.
//
// Debian's GDCM asserts (aborts) on damaged DICOM, and libhdf5 1.10 allocates and fills what a
// damaged superblock claims (4 GB for a 1 KB file, found by fuzz_hdf5). Such a library runs in
// a child process forked for the purpose, talking to vdiso over a socket: if it dies, the file
// is refused by name and vdiso goes on; its memory is bounded while it parses a file's
// metadata. io/readers/gdcm_process.h and io/readers/isolated_reader.h are built on this.
#pragma once

#include <sys/types.h>

#include <functional>
#include <string>

#include "io/error.h"
#include "io/readers/helper_wire.h"

namespace vdiso {

// A helper that died while serving a request: the file is refused (an IoError), and the fuzz
// harness can tell a contained library abort (SIGABRT, from an assertion) from a crash, a
// sanitizer report or an out-of-memory exit, which are findings (fuzz/fuzz_input.h).
class HelperDied : public IoError {
public:
    HelperDied(const std::string& message, int endSignal, int endStatus)
        : IoError(message), signal(endSignal), exitStatus(endStatus) {}
    int signal;      // the signal that ended it, or 0
    int exitStatus;  // its exit status when no signal ended it
};

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
    // Waits for the child after the socket failed and throws HelperDied: "<what>: <library>
    // <how it ended> <doing>: <advice>", how it ended being "was ended by signal 6 (an
    // assertion)" or "exited with status 1".
    [[noreturn]] void died(const std::string& what, const std::string& library,
                           const std::string& doing, const std::string& advice);

private:
    int mSocket = -1;
    pid_t mChild = -1;
};

// In the child: lifts the data memory bound set at the fork.
void liftMemoryBound();

}  // namespace vdiso
