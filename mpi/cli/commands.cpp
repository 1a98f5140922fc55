#include "mpi/cli/commands.h"

#include <cstdio>

#include "cli/args.h"
#include "io/atomic_output.h"

namespace vdiso::mpi::cli {

int exitCodeOf(const std::exception& e) { return vdiso::cli::exitCodeOf(e); }

void writeStats(const std::string& path, const std::string& json, bool overwrite) {
    const std::string text = json + "\n";
    if (path == "-") {
        std::fputs(text.c_str(), stdout);
    } else if (!path.empty()) {
        AtomicOutputFile out(path, overwrite);
        out.append(text.data(), text.size());
        out.commit();
    }
}

}  // namespace vdiso::mpi::cli
