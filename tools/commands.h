// The `vdiso` subcommands. Each parses its arguments into an options struct, calls one library
// entry point and prints; errors propagate to main() which prints them once.
#pragma once

namespace vdiso::cli {

int runConvert(int argc, char** argv);  // argv[0] is "convert"
int runIndex(int argc, char** argv);
int runSynth(int argc, char** argv);
int runInfo(int argc, char** argv);
int runExtract(int argc, char** argv);
int runCompare(int argc, char** argv);
int runServe(int argc, char** argv);

}  // namespace vdiso::cli
