// One output file that every rank of a job writes, appearing under its name only when all of
// them succeeded: what `vdiso-mpi extract` (collective_mesh.h) and `vdiso-mpi convert`
// (convert_across_ranks.h) write into.
//
// Rank 0 refuses an existing output (without `overwrite`; even with it, anything but a regular
// file, or one of the inputs under another name: io/atomic_output.h), creates an empty
// temporary file beside it, OUTPUT.partial.mpi.<pid>, and tells the others its name; they open
// it by that name (the same path on every node: a parallel file system). commit() links it
// into place (a rename with `overwrite`; without, link() refuses a file that appeared
// meanwhile). Until then the object removes the temporary on rank 0 when it goes, whatever
// happened. A rank killed outright (SIGKILL, the OOM killer) leaves it behind: unlike
// AtomicOutputFile's unnamed file, a file that other nodes open must have a name.
#pragma once

#include <string>
#include <vector>

#include "mpi/communicator.h"

namespace vdiso::mpi {

class RankSharedOutput {
public:
    // Collective. Throws RankFailure on every rank when rank 0 refuses the output or cannot
    // create the temporary (`inputs` matter on rank 0 only).
    RankSharedOutput(const Communicator& comm, std::string path, bool overwrite,
                     const std::vector<std::string>& inputs = {});
    ~RankSharedOutput();
    RankSharedOutput(const RankSharedOutput&) = delete;
    RankSharedOutput& operator=(const RankSharedOutput&) = delete;

    const std::string& path() const { return mPath; }
    const std::string& temporary() const { return mTemporary; }

    // Collective, once every rank has written, synced and closed the temporary and all agreed
    // they succeeded: rank 0 gives it the output's name. Throws RankFailure on every rank if
    // that fails (the temporary is then removed).
    void commit();

private:
    const Communicator& mComm;
    std::string mPath, mTemporary;
    bool mOverwrite, mCommitted = false;
};

}  // namespace vdiso::mpi
