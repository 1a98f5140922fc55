#include <cstdio>
#include <algorithm>
#include <cmath>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "app/store_info.h"
#include "cli/args.h"
#include "core/orientation.h"
#include "io/json.h"
#include "io/store/brick_store.h"
#include "io/store/external_bricks.h"
#include "tools/commands.h"

namespace vdiso::cli {

namespace {

constexpr const char* kHelp =
    "usage: vdiso info FILE.vdiso|URL [--iso V] [--json]\n"
    "\n"
    "Describes a brick store from its header and index alone (no brick is read):\n"
    "dimensions, type, spacing, origin, orientation, bricks, levels of detail (each level's bricks and stored\n"
    "bytes), compression, value range, histogram.\n"
    "\n"
    "  --iso V    also count the bricks that can hold isovalue V and the bytes they store\n"
    "             (a span-space query over the bricks' value ranges)\n"
    "  --json     one JSON object instead of text\n";

// The histogram as a row of block characters, heights on a log scale so that a few rare
// values (bone among tissue) still show.
std::string histogramSparkline(const ValueHistogram& h, int columns) {
    static const char* kBlocks[] = {" ", "▁", "▂", "▃", "▄", "▅", "▆", "▇", "█"};
    std::vector<double> col(size_t(columns), 0.0);
    for (int b = 0; b < kHistogramBins; ++b) col[size_t(b * columns / kHistogramBins)] += double(h.counts[size_t(b)]);
    double peak = 0;
    for (double& c : col) {
        c = std::log1p(c);
        peak = std::max(peak, c);
    }
    std::string out;
    for (double c : col) out += kBlocks[peak > 0 ? int(c / peak * 8 + 0.5) : 0];
    return out;
}

}  // namespace

int runInfo(int argc, char** argv) {
    Args args(argc, argv, 1);
    std::string path;
    std::optional<double> iso;
    bool json = false;
    RemoteOptions remote;
    while (!args.done()) {
        const std::string a = args.take();
        if (a == "--help" || a == "-h") {
            std::fputs(kHelp, stdout);
            std::fputs(kRemoteOptionsHelp, stdout);
            return 0;
        } else if (a == "--iso") {
            iso = parseDouble(a, args.value(a));
        } else if (a == "--json") {
            json = true;
        } else if (takeRemoteOption(a, args, remote)) {
        } else if (!a.empty() && a[0] == '-') {
            throw UsageError("unknown option '" + a + "'");
        } else if (path.empty()) {
            path = a;
        } else {
            throw UsageError("expects one FILE");
        }
    }
    if (path.empty()) throw UsageError("expects FILE.vdiso");

    const BrickStoreReader store(path, StoreOpenOptions{ReadMode::Buffered, remote});
    // A local store's whole index is read and checked, so that info refuses a store with a
    // corrupt part anywhere; a remote one's codes are not waited for (docs/remote.md).
    if (!store.remote()) store.subBlockCodes();
    const StoreHeader& h = store.header();
    const VolumeInfo& v = h.volume;
    const BrickLayout& l = store.layout();
    const ValueHistogram& hist = store.histogram();
    if (json) {
        std::printf("%s\n", storeInfoJson(store, iso).str().c_str());
        return 0;
    }
    const StoreFacts facts = storeFacts(store, iso);
    const double ratio = facts.compressionRatio;
    const std::vector<uint64_t>& bytesOfLevel = facts.levelBytes;
    const std::optional<ActiveBricks>& active = facts.active;
    // Integer samples have integer quantiles; the histogram's interpolation would suggest more.
    auto quantile = [&](double f) { return storeQuantile(store, f); };
    std::printf("%s\n", store.path().c_str());  // a URL without its query or user: as messages name it
    std::printf("  dimensions   %lld x %lld x %lld  %s\n", (long long)v.dims[0], (long long)v.dims[1],
                (long long)v.dims[2], scalarTypeName(v.type));
    std::printf("  spacing      %g x %g x %g   origin (%g, %g, %g)\n", v.spacing.x, v.spacing.y,
                v.spacing.z, v.origin.x, v.origin.y, v.origin.z);
    if (v.hasOrientation)
        std::printf("  orientation  axes i, j, k toward %s: LPS directions (%.4g, %.4g, %.4g) "
                    "(%.4g, %.4g, %.4g) (%.4g, %.4g, %.4g)\n",
                    axisSidesCode(v.direction).c_str(), v.direction[0].x, v.direction[0].y,
                    v.direction[0].z, v.direction[1].x, v.direction[1].y, v.direction[1].z,
                    v.direction[2].x, v.direction[2].y, v.direction[2].z);
    else
        std::printf("  orientation  none (the input gave none, or the store predates format 4)\n");
    std::printf("  bricks       %lld (%lld x %lld x %lld) of %d^3 cells, stored %d^3 samples\n",
                (long long)l.brickCount(), (long long)l.brickCounts[0], (long long)l.brickCounts[1],
                (long long)l.brickCounts[2], h.brickSize, l.side());
    for (size_t k = 0; k < bytesOfLevel.size() && bytesOfLevel.size() > 1; ++k) {
        const BrickLevel& level = store.levels()[k];
        std::printf("  level %-2zu     cells %3lldx  %lld x %lld x %lld samples  %6lld bricks", k,
                    (long long)(int64_t(1) << k), (long long)level.volume.dims[0],
                    (long long)level.volume.dims[1], (long long)level.volume.dims[2],
                    (long long)level.layout.brickCount());
        // An index's levels that lie in the indexed data have no bytes here.
        if (store.external() && int(k) < store.external()->levelCount()) std::printf("  in the data\n");
        else if (k > 0 && bytesOfLevel[0] > 0)
            std::printf("  %8.1f MB  (%.2f%% of level 0)\n", bytesOfLevel[k] / 1e6,
                        100.0 * double(bytesOfLevel[k]) / double(bytesOfLevel[0]));
        else std::printf("  %8.1f MB\n", bytesOfLevel[k] / 1e6);
    }
    if (bytesOfLevel.size() == 1) std::printf("  levels       1 (no coarser levels of detail)\n");
    if (const ExternalBricks* external = store.external()) {  // level 0 lies in the indexed array
        const int n = external->levelCount();
        const std::string which = n == 1 ? "level 0's" : "levels 0-" + std::to_string(n - 1) + "'s (its own scales)";
        std::printf("  indexes      %s: %s samples read from its chunks; this index %.2f MB\n",
                    external->name().c_str(), which.c_str(), store.fileBytes() / 1e6);
    }
    else
        std::printf("  stored       %.1f MB on disk for %.1f MB of samples (%s, ratio %.2f)\n",
                    store.fileBytes() / 1e6, v.byteSize() / 1e6, compressionName(h.compression), ratio);
    std::printf("  values       %g .. %g   1%% %.4g  median %.4g  99%% %.4g\n", h.valueMin,
                h.valueMax, quantile(0.01), quantile(0.5), quantile(0.99));
    std::printf("  histogram    |%s|  (log scale, %g .. %g)\n",
                histogramSparkline(hist, 64).c_str(), hist.lo, hist.hi);
    if (active)
        std::printf("  iso %-8g %zu of %lld bricks active (%.1f%%), %.1f MB stored (%.1f%%)\n",
                    *iso, active->bricks, (long long)l.brickCount(),
                    100.0 * double(active->bricks) / double(l.brickCount()),
                    active->storedBytes / 1e6,
                    100.0 * double(active->storedBytes) / double(bytesOfLevel[0]));
    return 0;
}

}  // namespace vdiso::cli
