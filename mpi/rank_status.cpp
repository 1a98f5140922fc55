#include "mpi/rank_status.h"

namespace vdiso::mpi {

void agreeAllSucceeded(const Communicator& comm, bool failed, const std::string& message, int exitCode) {
    const int first = comm.min(failed ? comm.rank() : comm.size());
    if (first == comm.size()) return;
    const std::string text = comm.broadcast(message, first);
    const int code = comm.broadcast(exitCode, first);
    throw RankFailure(first, code, text);
}

}  // namespace vdiso::mpi
