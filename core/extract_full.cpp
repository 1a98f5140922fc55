#include "core/extract_full.h"

#include <algorithm>
#include <chrono>

#include "core/minmax_tree.h"
#include "core/span_space.h"

namespace vdiso {

namespace {

using Clock = std::chrono::steady_clock;

double secondsSince(Clock::time_point start) {
    return std::chrono::duration<double>(Clock::now() - start).count();
}

// Progress every few dozen bricks: often enough for a bar, rare enough to cost nothing.
constexpr int64_t kProgressEvery = 32;

}  // namespace

FullExtractStats extractOctree(BrickSource& source, const FullExtractOptions& options,
                               TriangleMesh& mesh, const ProgressFn& progress) {
    const auto start = Clock::now();
    FullExtractStats stats;
    const MinMaxTree tree(source.layout(), source.brickRanges());
    std::vector<int64_t> bricks;
    stats.nodesVisited =
        tree.forEachActiveBrick(options.iso, [&](int64_t id) { bricks.push_back(id); });
    BrickExtractor extractor(source.volume(), source.layout(), options.metaCellSize);
    EdgeVertexMap seams;
    for (size_t i = 0; i < bricks.size(); ++i) {
        const BrickHandle brick = source.acquire(bricks[i]);
        extractor.extractBrick(bricks[i], brick.samples(), options.iso, mesh, seams);
        if (progress && (i % kProgressEvery == 0 || i + 1 == bricks.size()))
            progress(double(i + 1) / double(bricks.size()));
    }
    stats.bricksActive = int64_t(bricks.size());
    stats.metaCellsActive = extractor.counters().metaCellsActive;
    stats.cellsActive = extractor.counters().cellsActive;
    stats.extractSeconds = secondsSince(start);
    return stats;
}

FullExtractStats extractNoise(BrickSource& source, const FullExtractOptions& options,
                              TriangleMesh& mesh, const ProgressFn& progress) {
    FullExtractStats stats;
    const BrickLayout& layout = source.layout();
    BrickExtractor extractor(source.volume(), layout, options.metaCellSize);
    const uint32_t perBrick = uint32_t(extractor.metaCellsPerBrick());

    // Preprocessing, independent of the isovalue: the range of every meta-cell.
    auto start = Clock::now();
    std::vector<float> mins, maxs;
    mins.reserve(size_t(layout.brickCount()) * perBrick);
    maxs.reserve(mins.capacity());
    std::vector<BrickRange> ranges;
    for (int64_t id = 0; id < layout.brickCount(); ++id) {
        const BrickHandle brick = source.acquire(id);
        extractor.metaCellRanges(id, brick.samples(), ranges);
        for (const BrickRange& r : ranges) {
            mins.push_back(r.minValue);
            maxs.push_back(r.maxValue);
        }
        if (progress && id % kProgressEvery == 0) progress(0.5 * double(id) / double(layout.brickCount()));
    }
    const SpanSpaceTree tree(mins, maxs);
    stats.preprocessSeconds = secondsSince(start);

    // The query, then extraction grouped by brick (ids are brick * perBrick + meta-cell).
    start = Clock::now();
    std::vector<uint32_t> active;
    tree.query(options.iso, active);
    std::sort(active.begin(), active.end());
    stats.nodesVisited = int64_t(active.size());
    EdgeVertexMap seams;
    std::vector<uint32_t> local;
    for (size_t i = 0; i < active.size();) {
        const int64_t id = active[i] / perBrick;
        local.clear();
        for (; i < active.size() && active[i] / perBrick == uint32_t(id); ++i)
            local.push_back(active[i] % perBrick);
        const BrickHandle brick = source.acquire(id);
        extractor.extractMetaCells(id, brick.samples(), options.iso, local, mesh, seams);
        ++stats.bricksActive;
        if (progress) progress(0.5 + 0.5 * double(i) / double(active.size()));
    }
    stats.metaCellsActive = extractor.counters().metaCellsActive;
    stats.cellsActive = extractor.counters().cellsActive;
    stats.extractSeconds = secondsSince(start);
    return stats;
}

}  // namespace vdiso
