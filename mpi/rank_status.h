// Ending a job cleanly when any rank fails: each phase of a command runs on every rank, and
// then all ranks agree whether every one succeeded (an all-reduce of the first failing rank),
// so no rank waits forever in a collective call that a failed rank never makes.
//
// If one failed, the first failing rank's message and exit code are broadcast and every rank
// throws the same RankFailure: each then cleans up (the temporary output file, say) and exits
// with that code, and rank 0 alone prints the message. No MPI_Abort, which would leave files
// behind.
#pragma once

#include <stdexcept>
#include <string>
#include <utility>

#include "mpi/communicator.h"

namespace vdiso::mpi {

// What every rank throws after a phase some rank failed in.
class RankFailure : public std::runtime_error {
public:
    RankFailure(int rank, int exitCode, const std::string& message)
        : std::runtime_error("rank " + std::to_string(rank) + ": " + message),
          mRank(rank),
          mExitCode(exitCode),
          mMessage(message) {}
    int rank() const { return mRank; }     // the first (lowest) rank that failed
    int exitCode() const { return mExitCode; }
    const std::string& message() const { return mMessage; }  // without the rank

private:
    int mRank, mExitCode;
    std::string mMessage;
};

// Collective. `failed`: whether this rank failed, with its message and exit code (1 for an
// error, 2 for wrong usage). Returns when no rank failed; otherwise throws RankFailure on
// every rank.
void agreeAllSucceeded(const Communicator& comm, bool failed, const std::string& message = {},
                       int exitCode = 1);

// Runs phase() on this rank, catching what it throws, then agreeAllSucceeded. `exitCodeOf(e)`
// maps an exception to its exit code (to tell usage errors apart), `messageOf(e)` to what is
// said of it (a front end adds its flags to the library's words).
template <class Phase, class ExitCodeOf, class MessageOf>
void runPhase(const Communicator& comm, Phase&& phase, ExitCodeOf&& exitCodeOf, MessageOf&& messageOf) {
    bool failed = false;
    std::string message;
    int code = 1;
    try {
        phase();
    } catch (const RankFailure&) {
        throw;  // already agreed on (a collective call inside the phase)
    } catch (const std::exception& e) {
        failed = true;
        message = messageOf(e);
        code = exitCodeOf(e);
    }
    agreeAllSucceeded(comm, failed, message, code);
}

template <class Phase, class ExitCodeOf>
void runPhase(const Communicator& comm, Phase&& phase, ExitCodeOf&& exitCodeOf) {
    runPhase(comm, std::forward<Phase>(phase), std::forward<ExitCodeOf>(exitCodeOf),
             [](const std::exception& e) { return std::string(e.what()); });
}

// The same, every exception an error (exit code 1).
template <class Phase>
void runPhase(const Communicator& comm, Phase&& phase) {
    runPhase(comm, std::forward<Phase>(phase), [](const std::exception&) { return 1; });
}

}  // namespace vdiso::mpi
