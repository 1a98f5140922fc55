// vdiso-mpi convert: vdiso convert's command line (cli/convert_args.h) with the ranks of the
// job sharing the work (mpi/convert_across_ranks.h).
#include <cstdio>
#include <string>

#include <tbb/global_control.h>

#include "cli/args.h"
#include "cli/convert_args.h"
#include "io/atomic_output.h"
#include "io/json.h"
#include "io/process_stats.h"
#include "io/readers/volume_open.h"
#include "mpi/cli/commands.h"
#include "mpi/convert_across_ranks.h"
#include "mpi/rank_status.h"

namespace vdiso::mpi::cli {

namespace {

using vdiso::cli::Args;
using vdiso::cli::ConvertArgParser;
using vdiso::cli::ConvertArgs;
using vdiso::cli::kConvertInputHelp;
using vdiso::cli::kRemoteOptionsHelp;
using vdiso::cli::kStoreWriteOptionsHelp;
using vdiso::cli::parseInt;
using vdiso::cli::printConvertSummary;
using vdiso::cli::refuseExistingOutputs;
using vdiso::cli::UsageError;

constexpr const char* kHelp =
    "usage: mpirun -np N vdiso-mpi convert INPUT OUTPUT.vdiso [options]\n"
    "       mpirun -np N vdiso-mpi convert SLICE... OUTPUT.vdiso [options]\n"
    "\n"
    "Converts a volume into a brick store with the ranks of the job: each opens the input\n"
    "itself (the same path on every node: a parallel file system), reads its own slab of\n"
    "z-slices and writes its bricks into the one output; the coarser levels are made from the\n"
    "slabs, with the few slices at their borders exchanged. The store is the one 'vdiso\n"
    "convert' writes, brick for brick; only where each brick lies in the file differs. It\n"
    "appears only when every rank succeeded; a failure on any rank leaves none. Compressed\n"
    "inputs (.nii.gz, gzip NRRD or MetaImage) cannot be sought in: every rank decompresses\n"
    "them up to its slab.\n"
    "\n";

constexpr const char* kHelpEnd =
    "under MPI:\n"
    "  --stats STATS.json      statistics, written by rank 0, with \"ranks\" and \"per_rank\"\n"
    "                          ('-' for stdout)\n"
    "  --threads N             compression threads per rank (default 1: the ranks are the\n"
    "                          parallelism)\n"
    "other:\n"
    "  --quiet                 no summary\n"
    "store:\n";

struct MpiConvertCli {
    ConvertArgs convert;
    std::string statsPath;
    int threads = 1;
    bool help = false;
};

MpiConvertCli parseConvert(int argc, char** argv) {
    Args args(argc, argv, 1);
    MpiConvertCli o;
    ConvertArgParser parser;
    while (!args.done()) {
        const std::string a = args.take();
        if (a == "--help" || a == "-h") {
            o.help = true;
            return o;
        } else if (a == "--stats") {
            o.statsPath = args.value(a);
        } else if (a == "--threads") {
            o.threads = int(parseInt(a, args.value(a), 1, 1024));
        } else if (!parser.take(a, args)) {
            throw UsageError("unknown option '" + a + "'");
        }
    }
    o.convert = parser.finish();
    if (o.statsPath == o.convert.output) throw UsageError("--stats and OUTPUT are the same file");
    return o;
}

std::string statsJson(const MpiConvertCli& o, const RanksConvertResult& r) {
    const StoreWriteSummary& t = r.summary;
    const VolumeInfo& v = r.volume;
    JsonObject s;
    s.add("output", o.convert.output).add("input", r.sourceName).add("ranks", r.ranks);
    s.addRaw("dims", "[" + std::to_string(v.dims[0]) + ", " + std::to_string(v.dims[1]) + ", " +
                         std::to_string(v.dims[2]) + "]");
    s.add("type", scalarTypeName(v.type)).add("brick", o.convert.store.brickSize);
    s.add("compression", compressionName(o.convert.store.compression)).add("threads_per_rank", o.threads);
    s.add("levels", t.levels).add("bricks", t.bricks);
    s.add("level0_bytes", t.level0Bytes).add("coarse_bytes", t.coarseBytes);
    s.add("input_bytes", t.inputBytes).add("file_bytes", t.fileBytes).add("seconds", t.seconds);
    uint64_t bytesRead = 0, haloBytes = 0;
    std::string perRank = "[";
    for (size_t k = 0; k < r.perRank.size(); ++k) {
        const RankConvertFigures& f = r.perRank[k];
        bytesRead += f.bytesRead;
        haloBytes += f.haloBytesSent;
        JsonObject p;
        p.add("rank", int64_t(k)).add("first_layer", f.firstLayer).add("layers", f.layers);
        p.add("slices_skipped", f.slicesSkipped).add("bytes_read", f.bytesRead);
        p.add("bricks_written", f.bricksWritten).add("bytes_written", f.bytesWritten);
        p.add("halo_bytes_sent", f.haloBytesSent).add("seconds", f.seconds);
        perRank += (k ? ", " : "") + p.str();
    }
    // Read by all ranks together: the input once, plus the ghost slices read twice.
    s.add("bytes_read", bytesRead).add("halo_bytes", haloBytes);
    s.addRaw("per_rank", perRank + "]");
    s.add("peak_rss_mb_rank0", peakRssMb());
    return s.str();
}

}  // namespace

int runConvertAcrossRanks(const Communicator& comm, int argc, char** argv) {
    MpiConvertCli o;
    // Parsing: the same on every rank; existing outputs refused by rank 0 before any work.
    runPhase(comm, [&] {
        o = parseConvert(argc, argv);
        if (o.help || comm.rank() != 0) return;
        refuseExistingOutputs({&o.convert.output, &o.statsPath}, o.convert.store.overwrite);
    }, exitCodeOf, vdiso::cli::messageOf);
    if (o.help) {
        if (comm.rank() == 0) {
            std::fputs(kHelp, stdout);
            std::fputs(kConvertInputHelp, stdout);
            std::fputs(kHelpEnd, stdout);
            std::fputs(kStoreWriteOptionsHelp, stdout);
            std::fputs(kRemoteOptionsHelp, stdout);
        }
        return 0;
    }
    const tbb::global_control threads(tbb::global_control::max_allowed_parallelism, size_t(o.threads));
    RanksConvertOptions options;
    options.output = o.convert.output;
    options.store = o.convert.store;
    const RanksConvertResult result = convertAcrossRanks(
        comm, [&] { return openVolume(o.convert.inputs, o.convert.input); }, options);
    runPhase(comm, [&] {
        if (comm.rank() != 0) return;
        writeStats(o.statsPath, statsJson(o, result), o.convert.store.overwrite);
        if (o.convert.quiet || o.statsPath == "-") return;
        printConvertSummary(o.convert.output, " on " + std::to_string(result.ranks) + " ranks", result.volume,
                            result.summary, o.convert.store.brickSize, result.sourceName);
    }, exitCodeOf, vdiso::cli::messageOf);
    return 0;
}

}  // namespace vdiso::mpi::cli
