// vdiso-mpi: vdiso's commands shared among the ranks of an mpirun job. A separate executable,
// so that vdiso itself neither links nor starts MPI. The commands are in mpi/cli/commands.h;
// what is not under MPI is refused with a message saying so.
//
// Errors: every rank parses the same argv, so usage errors are the same on all of them and
// rank 0 alone prints them; a failure while working is agreed on collectively
// (mpi/rank_status.h) and rank 0 prints the first failing rank's message. Every rank then
// exits with the same code: 2 for wrong usage, 1 for an error.
#include <cstdio>
#include <cstring>
#include <exception>
#include <string>

#include "mpi/cli/commands.h"
#include "mpi/communicator.h"
#include "mpi/rank_status.h"

namespace {

using namespace vdiso;

constexpr const char* kUsage =
    "usage: mpirun -np N vdiso-mpi <command> [options]\n"
    "\n"
    "commands (under MPI so far):\n"
    "  convert INPUT OUTPUT.vdiso [options]   vdiso convert's command line, shared by the ranks:\n"
    "                                         each reads and bricks its own slab, one store\n"
    "  extract FILE.vdiso --iso V [options]   vdiso extract's command line, shared by the ranks:\n"
    "                                         octree (one welded PLY or STL written together), sage\n"
    "                                         and wise (by parts of the image or of the volume)\n"
    "\n"
    "synth, info, compare and serve are not yet under MPI: run them with vdiso.\n";

}  // namespace

int main(int argc, char** argv) {
    mpi::MpiSession session(argc, argv);
    const mpi::Communicator comm;
    const bool printer = comm.rank() == 0;
    if (argc < 2 || !std::strcmp(argv[1], "--help") || !std::strcmp(argv[1], "-h")) {
        if (printer) std::fputs(kUsage, argc < 2 ? stderr : stdout);
        return argc < 2 ? 2 : 0;
    }
    const std::string command = argv[1];
    try {
        if (command == "extract") return mpi::cli::runExtractAcrossRanks(comm, argc - 1, argv + 1);
        if (command == "convert") return mpi::cli::runConvertAcrossRanks(comm, argc - 1, argv + 1);
        if (printer) {
            if (command == "synth" || command == "info" || command == "compare" ||
                command == "serve")
                std::fprintf(stderr, "vdiso-mpi: %s is not yet under MPI: run it with vdiso\n", command.c_str());
            else
                std::fprintf(stderr, "vdiso-mpi: unknown command '%s'\n\n%s", command.c_str(), kUsage);
        }
        return 2;
    } catch (const mpi::RankFailure& e) {
        if (printer) {
            if (e.exitCode() == 2)  // wrong usage: the same on every rank, so no rank to name
                std::fprintf(stderr, "vdiso-mpi %s: %s (see 'vdiso-mpi %s --help')\n", command.c_str(),
                             e.message().c_str(), command.c_str());
            else
                std::fprintf(stderr, "vdiso-mpi %s: %s\n", command.c_str(), e.what());
        }
        return e.exitCode();
    } catch (const std::exception& e) {
        // Not agreed on: reached by every rank alike (a collective call that failed everywhere).
        if (printer) std::fprintf(stderr, "vdiso-mpi %s: rank %d: %s\n", command.c_str(), comm.rank(), e.what());
        return 1;
    }
}
