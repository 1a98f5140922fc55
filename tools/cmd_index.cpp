#include <algorithm>
#include <cstdio>
#include <filesystem>

#include "cli/args.h"
#include "cli/progress_bar.h"
#include "io/remote/remote_file.h"
#include "io/store/zarr_index.h"
#include "tools/commands.h"

namespace vdiso::cli {

namespace {

constexpr const char* kHelp =
    "usage: vdiso index DATA [--index OUT] [options]\n"
    "\n"
    "Indexes a Zarr array or OME-Zarr image (v2 or v3; a folder, or https://, http://, s3://)\n"
    "where it lies, so that every command opens it like a store without converting it: DATA is\n"
    "read once, and the index holds each brick's value range, the sub-block ranges that cull\n"
    "reads, the histogram and coarser levels of detail, with each chunk's size and checksum:\n"
    "a chunk that changes afterwards is refused when read. Then 'vdiso extract DATA ...' (a\n"
    "folder finds its index beside it) or 'vdiso extract OUT ...'.\n"
    "\n"
    "An OME-Zarr's first coarser scale is level 1 where it fits (2x level 0 on x, y and z, at\n"
    "its origin): read once too and left where it lies, which keeps out of the index the one\n"
    "coarse level that weighs (an eighth of the data). The levels past it are filtered from it\n"
    "and kept in the index (2 % of the data or so): a coarser scale's chunks each cover much of\n"
    "the volume, which a view would fetch whole. --scale-levels N takes up to N scales; the\n"
    "summary says which scale was not taken, and why.\n"
    "\n"
    "The index is written as OUT.partial, and where the pass stands is saved as OUT.resume\n"
    "every half minute or so: a run that stops (Ctrl-C, a failed read, a kill) is gone on\n"
    "with by running the same command again. Both files go once OUT is written.\n"
    "\n"
    "  --index OUT             where the index goes (default: DATA.vdiso beside a local DATA;\n"
    "                          needed for a URL)\n"
    "  --scale-level N         the OME-Zarr multiscales level to index (default 0, the finest)\n"
    "  --scale-levels N        coarser levels taken from the image's own scales, at most N\n"
    "                          (default 1; 0: --own-levels)\n"
    "  --own-levels            make every coarser level with vdiso's filter and keep it in the\n"
    "                          index, rather than take the image's own scales\n"
    "  --restart               start over, not from an interrupted run's OUT.resume\n"
    "  --checkpoint-seconds S  save where the pass stands at least S seconds apart (default 30;\n"
    "                          never more often than ten times the time a save takes)\n"
    "  --quiet                 no progress bar or summary\n"
    "index:\n";

}  // namespace

int runIndex(int argc, char** argv) {
    Args args(argc, argv, 1);
    ZarrIndexOptions options;
    std::string data, index;
    bool quiet = false;
    while (!args.done()) {
        const std::string a = args.take();
        if (a == "--help" || a == "-h") {
            std::fputs(kHelp, stdout);
            std::fputs(kStoreWriteOptionsHelp, stdout);
            std::fputs(kRemoteOptionsHelp, stdout);
            return 0;
        }
        if (a == "--index") {
            index = args.value(a);
        } else if (a == "--scale-level") {
            options.level = int(parseInt(a, args.value(a), 0, 64));
        } else if (a == "--checkpoint-seconds") {
            options.checkpointSeconds = parseDouble(a, args.value(a));
            if (!(options.checkpointSeconds >= 0)) throw UsageError(a + " expects seconds, 0 or more");
        } else if (a == "--own-levels") {
            options.scaleLevels = 0;
        } else if (a == "--scale-levels") {
            options.scaleLevels = int(parseInt(a, args.value(a), 0, 16));
        } else if (a == "--restart") {
            options.restart = true;
        } else if (a == "--quiet") {
            quiet = true;
        } else if (takeStoreWriteOption(a, args, options.store) || takeRemoteOption(a, args, options.remote)) {
        } else if (!a.empty() && a[0] == '-') {
            throw UsageError("unknown option '" + a + "'");
        } else if (data.empty()) {
            data = a;
        } else {
            throw UsageError("expects one DATA, and the index's path after --index");
        }
    }
    if (data.empty()) throw UsageError("expects DATA, a Zarr array or OME-Zarr image");
    index = indexPathFor(data, index);
    ZarrIndexSummary s;
    try {
        s = indexZarr(data, index, options, progressBar("index", 0, quiet));
    } catch (...) {
        if (std::filesystem::exists(indexCheckpointPath(index)))
            std::fprintf(stderr, "\nvdiso index: %s keeps where the pass stood; the same command goes on from there\n",
                         indexCheckpointPath(index).c_str());
        throw;
    }
    if (!quiet) {
        if (!s.startedOver.empty()) std::printf("started over: %s\n", s.startedOver.c_str());
        if (s.store.resumedLayers > 0)
            std::printf("went on from an interrupted run: %lld of %lld layers of bricks were done\n",
                        (long long)s.store.resumedLayers, (long long)s.store.layers);
        if (s.ownScaleLevels > 0) {
            const std::string which = s.ownScaleLevels == 1 ? "level 1 from its own scale 1"
                                                              : "levels 1-" + std::to_string(s.ownScaleLevels) + " from its own scales";
            std::printf("%s, read where it lies%s\n", which.c_str(),
                        s.store.levels > s.ownScaleLevels + 1 ? "; the coarser ones filtered from it and kept here" : "");
            if (isRemoteLocation(data) && s.ownScaleLevels > 1)
                std::printf("(a view's coarse bricks come from those scales' whole chunks over the link; "
                            "--scale-levels 1 keeps the coarser ones in the index instead)\n");
        }
        if (!s.scalesNotUsed.empty()) std::printf("%s; the levels from there on are filtered\n", s.scalesNotUsed.c_str());
        const double ratio = double(s.store.fileBytes) / double(std::max<uint64_t>(s.dataBytes, 1));
        std::printf("wrote %s: %lld bricks of %d^3 cells in %d level%s over %lld chunks (%lld missing), "
                    "%.1f MB indexed into %.2f MB (%.2f%% of the data; coarse levels %.2f MB), %.2f s, %.0f MB/s\n",
                    index.c_str(), (long long)s.store.bricks, options.store.brickSize, s.store.levels,
                    s.store.levels == 1 ? "" : "s", (long long)s.chunks, (long long)s.missingChunks,
                    s.dataBytes / 1e6, s.store.fileBytes / 1e6, 100.0 * ratio, s.store.coarseBytes / 1e6,
                    s.store.seconds, s.store.inputBytes / 1e6 / s.store.seconds);
    }
    return 0;
}

}  // namespace vdiso::cli
