#include <cstdio>

#include "cli/args.h"
#include "cli/convert_args.h"
#include "cli/progress_bar.h"
#include "io/readers/volume_open.h"
#include "io/store/store_writer.h"
#include "tools/commands.h"

namespace vdiso::cli {

namespace {

constexpr const char* kHelp =
    "usage: vdiso convert INPUT OUTPUT.vdiso [options]\n"
    "       vdiso convert SLICE... OUTPUT.vdiso [options]   (DICOM files, TIFF slices)\n"
    "\n"
    "Converts a volume into a brick store, streaming: memory stays a few slabs whatever the\n"
    "volume's size. The output appears only when complete; a failure leaves none.\n"
    "\n";

constexpr const char* kHelpEnd =
    "other:\n"
    "  --quiet                 no progress bar or summary\n"
    "store:\n";

}  // namespace

int runConvert(int argc, char** argv) {
    Args args(argc, argv, 1);
    ConvertArgParser parser;
    while (!args.done()) {
        const std::string a = args.take();
        if (a == "--help" || a == "-h") {
            std::fputs(kHelp, stdout);
            std::fputs(kConvertInputHelp, stdout);
            std::fputs(kHelpEnd, stdout);
            std::fputs(kStoreWriteOptionsHelp, stdout);
            std::fputs(kRemoteOptionsHelp, stdout);
            return 0;
        }
        if (!parser.take(a, args)) throw UsageError("unknown option '" + a + "'");
    }
    const ConvertArgs c = parser.finish();
    const std::string& outPath = c.output;
    const StoreWriteOptions& store = c.store;
    const bool quiet = c.quiet;

    auto source = openVolume(c.inputs, c.input);
    const VolumeInfo& info = source->info();
    const StoreWriteSummary s = writeBrickStore(
        *source, outPath, store, progressBar("convert", double(info.byteSize()), quiet));
    if (!quiet) printConvertSummary(outPath, "", info, s, store.brickSize, source->name());
    return 0;
}

}  // namespace vdiso::cli
