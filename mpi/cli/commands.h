// vdiso-mpi's commands: each parses the same command line on every rank and runs collectively.
// Errors are agreed on (mpi/rank_status.h): RankFailure reaches main() on every rank alike.
#pragma once

#include "mpi/communicator.h"

namespace vdiso::mpi::cli {

int runExtractAcrossRanks(const Communicator& comm, int argc, char** argv);  // argv[0] is "extract"
int runConvertAcrossRanks(const Communicator& comm, int argc, char** argv);  // argv[0] is "convert"

}  // namespace vdiso::mpi::cli
