// The arguments of `vdiso convert`, which `vdiso-mpi convert` takes too: the input(s) and the
// output, each input format's options, the store's options and --quiet. One parser, so the two
// commands read the same command line alike; each adds its own options around it.
#pragma once

#include <string>
#include <vector>

#include "cli/args.h"
#include "io/readers/raw_reader.h"
#include "io/readers/volume_open.h"
#include "io/store/store_writer.h"

namespace vdiso::cli {

struct ConvertArgs {
    std::vector<std::string> inputs;  // one input, or several slice files (DICOM, TIFF)
    std::string output;
    InputOptions input;
    StoreWriteOptions store;
    bool quiet = false;
};

class ConvertArgParser {
public:
    // Consumes `flag` (with its value) when it is an input option, a store option (cli/args.h),
    // --quiet or a positional argument (not starting with '-', or "-"); returns false for any
    // other option, which the caller takes or refuses. Throws UsageError for a bad value.
    bool take(const std::string& flag, Args& args);
    // Checks what was taken as a whole (INPUT and OUTPUT given, raw options together, ...):
    // throws UsageError with one sentence.
    ConvertArgs finish();

private:
    ConvertArgs mArgs;
    RawOptions mRaw;
    std::vector<std::string> mPositional;
    bool mDimsGiven = false, mTypeGiven = false, mRawOnlyGiven = false;
};

// Prints what a conversion wrote, in two lines: the store (size, bricks, levels, ratio, speed;
// `where` after the output's name, such as " on 4 ranks") and where its meshes will lie.
void printConvertSummary(const std::string& output, const std::string& where, const VolumeInfo& info,
                         const StoreWriteSummary& s, int brickSize, const std::string& sourceName);

// Help for the input formats and their options, from "input formats" to the OpenVDB lines.
extern const char* const kConvertInputHelp;

}  // namespace vdiso::cli
