// Progress for long commands: a bar on stderr when it is a terminal, nothing otherwise; and,
// either way, Ctrl-C turned into an exception at the next progress call, so the operation
// unwinds and removes its partial output.
#pragma once

#include <string>

#include "core/progress.h"

namespace vdiso::cli {

// Installs the SIGINT handler; call once at start-up.
void installInterruptHandler();

// A progress callback labelled `label`; `bytesTotal` (if non-zero) adds a throughput figure.
ProgressFn progressBar(const std::string& label, double bytesTotal = 0, bool quiet = false);

}  // namespace vdiso::cli
