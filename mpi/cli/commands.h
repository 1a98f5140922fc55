// vdiso-mpi's commands: each parses the same command line on every rank and runs collectively.
// Errors are agreed on (mpi/rank_status.h): RankFailure reaches main() on every rank alike.
#pragma once

#include <exception>
#include <string>

#include "mpi/communicator.h"

namespace vdiso::mpi::cli {

// The exit code of a phase's exception: vdiso's (cli/args.h exitCodeOf).
int exitCodeOf(const std::exception& e);

// Rank 0's statistics: `json` and a newline to stdout for "-", else to the file, whole or not at
// all (AtomicOutputFile).
void writeStats(const std::string& path, const std::string& json, bool overwrite);

int runExtractAcrossRanks(const Communicator& comm, int argc, char** argv);  // argv[0] is "extract"
int runConvertAcrossRanks(const Communicator& comm, int argc, char** argv);  // argv[0] is "convert"

}  // namespace vdiso::mpi::cli
