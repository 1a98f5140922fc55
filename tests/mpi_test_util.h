// Running vdiso-mpi under mpirun from the tests (test_mpi_cli.cpp, test_mpi_convert.cpp), and
// reading numbers back from its --stats. Only where MPI was found (VDISO_MPI_COMMAND defined).
#pragma once

#ifdef VDISO_MPI_COMMAND

#include <cstdint>
#include <regex>
#include <string>
#include <utility>
#include <vector>

#include "tests/test_util.h"

namespace vdiso::test {

// CI runs as root, which OpenMPI refuses unless told twice. Under AddressSanitizer, leak
// detection is off for the ranks: OpenMPI leaves some 120 KB of its own allocations at
// MPI_Finalize, from components it has already unloaded (so no suppression can name them). The
// same code is leak-checked in vdiso's own tests; ASan's other checks and UBSan stay.
inline std::string mpirunPrefix() {
    const std::string leaks = VDISO_UNDER_ASAN ? "ASAN_OPTIONS=\"${ASAN_OPTIONS:-}:detect_leaks=0\" " : "";
    return "OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 " + leaks + std::string(VDISO_MPI_COMMAND) +
           " --oversubscribe";
}

// `ranks` ranks of vdiso-mpi with `args` (oversubscribed: the machine may have fewer cores).
inline CommandResult runMpi(int ranks, const std::string& args) {
    return runCommand(mpirunPrefix() + " -np " + std::to_string(ranks) + " " + VDISO_MPI_BINARY + " " + args);
}

// One job whose ranks run with different arguments (mpirun's "-np A prog args : -np B prog
// args"), rank numbers in the order given: a node that sees another input, say.
inline CommandResult runMpiGroups(const std::vector<std::pair<int, std::string>>& groups) {
    std::string line = mpirunPrefix();
    for (size_t g = 0; g < groups.size(); ++g)
        line += (g ? " : -np " : " -np ") + std::to_string(groups[g].first) + " " + VDISO_MPI_BINARY + " " +
                groups[g].second;
    return runCommand(line);
}

// The values of `"key": N` in `json`, in order (per_rank's entries after the totals).
inline std::vector<uint64_t> numbers(const std::string& json, const std::string& key) {
    std::vector<uint64_t> out;
    const std::regex re("\"" + key + "\": (-?[0-9]+)");
    for (auto it = std::sregex_iterator(json.begin(), json.end(), re); it != std::sregex_iterator(); ++it)
        out.push_back(uint64_t(std::stoll((*it)[1])));
    return out;
}

}  // namespace vdiso::test

#endif  // VDISO_MPI_COMMAND
