#include "mpi/shared_output.h"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>

#include "io/atomic_output.h"
#include "io/error.h"
#include "mpi/rank_status.h"

namespace vdiso::mpi {

RankSharedOutput::RankSharedOutput(const Communicator& comm, std::string path, bool overwrite,
                                   const std::vector<std::string>& inputs)
    : mComm(comm), mPath(std::move(path)), mOverwrite(overwrite) {
    std::string temporary;
    runPhase(comm, [&] {
        if (comm.rank() != 0) return;
        checkOutputReplaceable(mPath, overwrite, inputs);
        temporary = mPath + ".partial.mpi." + std::to_string(::getpid());
        // Empty, also if an earlier run under the same process id left one.
        const int fd = ::open(temporary.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
        if (fd < 0) throwSystemError(mPath, "cannot write its temporary file " + temporary, errno);
        mTemporary = temporary;  // ours from here: removed when we go
        ::close(fd);
    });
    mTemporary = comm.broadcast(temporary, 0);
}

RankSharedOutput::~RankSharedOutput() {
    if (!mCommitted && mComm.rank() == 0 && !mTemporary.empty()) std::remove(mTemporary.c_str());
}

void RankSharedOutput::commit() {
    runPhase(mComm, [&] {
            if (mComm.rank() != 0) return;
            if (mOverwrite) {
                if (std::rename(mTemporary.c_str(), mPath.c_str()) != 0)
                    throwIoError(mPath, std::string("cannot rename into place: ") + std::strerror(errno));
            } else {
                if (::link(mTemporary.c_str(), mPath.c_str()) != 0)
                    throwIoError(mPath, errno == EEXIST ? std::string("already exists (pass --force to replace it)")
                                                        : std::string("cannot link into place: ") + std::strerror(errno));
                ::unlink(mTemporary.c_str());
            }
    });  // on failure the destructor removes the temporary
    mCommitted = true;
}

}  // namespace vdiso::mpi
