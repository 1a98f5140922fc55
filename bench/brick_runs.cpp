// How few requests could read the bricks a SAGE view reads (issue: remote views at the speed of
// the link): the bricks of one view, as `vdiso extract --method sage` takes them (its settings,
// levels of detail included), and the ranges they make
//   - in the store's file order, each run of bricks stored one after another one range (the
//     least a remote view could ask for if it knew every brick at once; a real view asks more:
//     it finds bricks as it goes);
//   - in that order, reading through gaps of up to 16 KB .. 4 MB (what coalescing costs in bytes);
//   - in Morton orders within blocks of 2, 4 or 8 bricks a side (3-D) or per layer (2-D), as a
//     new store layout could write them (x order within layers for blocks of 1).
//
//   vdiso_brick_runs STORE.vdiso ISO [distant|normal|closeup] [SIZE]    (default normal 1024)
#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <mutex>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "app/extract_settings.h"
#include "cache/brick_cache.h"
#include "core/camera.h"
#include "core/extract/extract_view.h"
#include "core/view_presets.h"
#include "io/store/brick_store.h"

using namespace vdiso;

namespace {

// Every brick the view takes (any use), whichever strip takes it.
struct BricksTaken final : ViewStream {
    std::mutex mutex;
    std::set<int64_t> ids;
    bool beginBrick(int64_t brick, int, double, Use& use) override {
        std::lock_guard lock(mutex);
        ids.insert(brick);
        use = Use::Part;
        return true;
    }
    void endBrick(int64_t, Use, const TriangleMesh&, const PointSet&, const TriangleMesh&) override {}
};

// Bit interleaving of 3 (or 2) coordinates below 1024.
uint64_t morton3(uint64_t x, uint64_t y, uint64_t z) {
    uint64_t r = 0;
    for (int b = 0; b < 10; ++b) r |= (x >> b & 1) << (3 * b) | (y >> b & 1) << (3 * b + 1) | (z >> b & 1) << (3 * b + 2);
    return r;
}
uint64_t morton2(uint64_t x, uint64_t y) {
    uint64_t r = 0;
    for (int b = 0; b < 16; ++b) r |= (x >> b & 1) << (2 * b) | (y >> b & 1) << (2 * b + 1);
    return r;
}

// The coordinates whose blockRank is `rank` (none beyond the layout's bricks: false).
bool brickAtRank(const BrickLayout& layout, uint64_t rank, int block, bool threeD, Dims3& c) {
    const int64_t bx = (layout.brickCounts[0] + block - 1) / block, by = (layout.brickCounts[1] + block - 1) / block;
    const uint64_t per = threeD ? uint64_t(block * block * block) : uint64_t(block * block);
    const uint64_t b = rank / per, m = rank % per;
    uint64_t x = 0, y = 0, z = 0;
    for (int k = 0; k < 10; ++k) {
        if (threeD) {
            x |= (m >> (3 * k) & 1) << k;
            y |= (m >> (3 * k + 1) & 1) << k;
            z |= (m >> (3 * k + 2) & 1) << k;
        } else {
            x |= (m >> (2 * k) & 1) << k;
            y |= (m >> (2 * k + 1) & 1) << k;
        }
    }
    const int64_t blockX = int64_t(b) % bx, blockY = int64_t(b) / bx % by, blockZ = int64_t(b) / bx / by;
    c = {blockX * block + int64_t(x), blockY * block + int64_t(y),
         threeD ? blockZ * block + int64_t(z) : int64_t(b) / bx / by};
    return c[0] < layout.brickCounts[0] && c[1] < layout.brickCounts[1] && c[2] < layout.brickCounts[2];
}

// A brick's place in a layout of blocks of `block` bricks a side (3-D, or per layer: 2-D),
// blocks in x order, Morton order within each.
uint64_t blockRank(const BrickLayout& layout, const Dims3& c, int block, bool threeD) {
    const int64_t bx = (layout.brickCounts[0] + block - 1) / block, by = (layout.brickCounts[1] + block - 1) / block;
    if (threeD)
        return uint64_t((c[2] / block * by + c[1] / block) * bx + c[0] / block) * uint64_t(block * block * block) +
               morton3(uint64_t(c[0] % block), uint64_t(c[1] % block), uint64_t(c[2] % block));
    return uint64_t((c[2] * by + c[1] / block) * bx + c[0] / block) * uint64_t(block * block) +
           morton2(uint64_t(c[0] % block), uint64_t(c[1] % block));
}

}  // namespace

int main(int argc, char** argv) {
    if (argc < 3) {
        std::fprintf(stderr, "usage: vdiso_brick_runs STORE.vdiso ISO [distant|normal|closeup] [SIZE]\n");
        return 2;
    }
    const BrickStoreReader store(argv[1]);
    BrickCache cache(store, uint64_t(4) << 30);
    const std::string view = argc > 3 ? argv[3] : "normal";
    const int size = argc > 4 ? std::atoi(argv[4]) : 1024;
    const ViewPreset preset = view == "distant" ? ViewPreset::Distant : view == "closeup" ? ViewPreset::Closeup
                                                                                          : ViewPreset::Normal;
    const VolumeInfo& volume = store.volume();
    const Camera camera = presetCamera(preset, volume.origin, volume.worldMax(), size, size);
    ExtractSettings settings;
    settings.method = "sage";
    settings.iso = std::atof(argv[2]);
    ViewExtractOptions options = viewExtractOptions(settings, CachePlan{0, 1});
    BricksTaken taken;
    options.stream = &taken;
    streamViewDependent(cache, camera, options);

    const std::span<const BrickEntry> index = store.index();
    std::vector<int64_t> ids(taken.ids.begin(), taken.ids.end());
    std::sort(ids.begin(), ids.end(), [&](int64_t a, int64_t b) { return index[size_t(a)].offset < index[size_t(b)].offset; });
    uint64_t bytes = 0;
    size_t runs = 0;
    for (size_t k = 0; k < ids.size(); ++k) {
        bytes += index[size_t(ids[k])].storedBytes;
        runs += k == 0 || !store.readsTogether(ids[k - 1], ids[k]);
    }
    std::printf("%s, iso %s, %s view at %d: %zu bricks, %.1f MB; %zu runs in the file\n", argv[1], argv[2],
                view.c_str(), size, ids.size(), double(bytes) / 1e6, runs);
    for (const uint64_t gap : {uint64_t(16) << 10, uint64_t(64) << 10, uint64_t(256) << 10, uint64_t(1) << 20,
                               uint64_t(4) << 20}) {
        size_t ranges = 0;
        uint64_t read = 0, begin = 0, end = 0;
        for (size_t k = 0; k < ids.size(); ++k) {
            const BrickEntry& e = index[size_t(ids[k])];
            if (k == 0 || e.offset > end + gap) {
                read += end - begin;
                ++ranges;
                begin = e.offset;
            }
            end = std::max(end, e.offset + e.storedBytes);
        }
        read += end - begin;
        std::printf("  through gaps up to %5llu KB: %zu ranges, %.1f MB (%.2fx)\n", (unsigned long long)(gap >> 10),
                    ranges, double(read) / 1e6, double(read) / double(bytes));
    }
    const std::vector<BrickLevel>& levels = store.levels();
    for (const bool threeD : {false, true})
        for (const int block : {1, 2, 4, 8}) {
            if (threeD && block == 1) continue;
            std::vector<std::pair<int, uint64_t>> ranks;  // (level, place)
            for (const int64_t id : ids) {
                int level = 0;
                while (level + 1 < int(levels.size()) && id >= levels[size_t(level) + 1].firstBrick) ++level;
                const BrickLayout& layout = levels[size_t(level)].layout;
                ranks.emplace_back(level, blockRank(layout, layout.brickCoord(id - levels[size_t(level)].firstBrick),
                                                    block, threeD));
            }
            std::sort(ranks.begin(), ranks.end());
            size_t together = 0, withGaps = 0;  // runs; runs through one-brick gaps
            uint64_t gapBytes = 0;                // of the bricks read through
            for (size_t k = 0; k < ranks.size(); ++k) {
                const bool sameLevel = k > 0 && ranks[k].first == ranks[k - 1].first;
                together += !(sameLevel && ranks[k].second == ranks[k - 1].second + 1);
                withGaps += !(sameLevel && ranks[k].second <= ranks[k - 1].second + 2);
                const BrickLevel& at = levels[size_t(ranks[k].first)];
                Dims3 c;
                if (sameLevel && ranks[k].second == ranks[k - 1].second + 2 &&
                    brickAtRank(at.layout, ranks[k].second - 1, block, threeD, c))
                    gapBytes += index[size_t(at.firstBrick + at.layout.brickId(c[0], c[1], c[2]))].storedBytes;
            }
            std::printf("  %s blocks of %d: %zu runs (%zu through one-brick gaps, %.2fx the bytes)\n",
                        block == 1 ? "x order," : threeD ? "Morton 3-D," : "Morton 2-D,", block, together, withGaps,
                        double(bytes + gapBytes) / double(bytes));
        }
    return 0;
}
