#include "io/store/store_writer.h"

#include <algorithm>
#include <chrono>
#include <functional>
#include <future>
#include <memory>
#include <sstream>
#include <stdexcept>
#include <vector>

#include <unistd.h>

#include "core/brick_levels.h"
#include "core/interrupt.h"
#include "io/atomic_output.h"
#include "io/store/brick_encoder.h"
#include "io/store/store_checkpoint.h"

namespace vdiso {

namespace {

// A coarser level being made: its slices as they are filtered from the level below, and the
// next of its layers of bricks to encode.
struct LevelInProgress {
    BrickLevel level;
    std::unique_ptr<MappedSlices> ring;
    int64_t nextSlice = 0;
    int64_t nextLayer = 0;
};

using Clock = std::chrono::steady_clock;

double secondsSince(Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); }

}  // namespace

std::string storeResumeIdentity(const VolumeInfo& volume, const std::string& sourceName,
                                const StoreWriteOptions& options, const std::string& sourceIdentity) {
    const VolumeInfo info = storeVolumeFor(volume, options, sourceName);
    std::ostringstream s;
    s << std::hexfloat << "store " << kStoreFormatVersion << "; dims " << info.dims[0] << ' ' << info.dims[1] << ' '
      << info.dims[2] << "; type " << int(info.type) << "; spacing " << info.spacing.x << ' ' << info.spacing.y << ' '
      << info.spacing.z << "; origin " << info.origin.x << ' ' << info.origin.y << ' ' << info.origin.z
      << "; direction";
    for (int c = 0; c < 3; ++c)
        for (int r = 0; r < 3; ++r) s << ' ' << info.direction[c][r];
    s << ' ' << info.hasOrientation << "; brick " << options.brickSize << "; levels "
      << storeLevelCount(BrickLayout(info.dims, options.brickSize), options) << "; compression "
      << int(options.compression) << ' ' << options.compressionLevel << ' ' << options.shuffle << "; external "
      << bool(options.externalRecord) << "; " << sourceIdentity;
    return s.str();
}

StoreWriteSummary writeBrickStore(SliceReader& source, const std::string& outPath,
                                  const StoreWriteOptions& options, const ProgressFn& progress) {
    const auto start = Clock::now();
    const VolumeInfo info = storeVolumeFor(source.info(), options, source.name());
    const BrickLayout layout(info.dims, options.brickSize);
    const size_t sampleBytes = scalarSize(info.type);
    const int B = options.brickSize;
    const int levelCount = storeLevelCount(layout, options);
    const std::vector<BrickLevel> levels = brickLevels(info, B, levelCount);
    // Level l's (>= 1) own source (an OME-Zarr's scale), if any.
    auto coarseSource = [&](size_t l) -> SliceReader* {
        return l <= options.coarseSources.size() ? options.coarseSources[l - 1] : nullptr;
    };
    for (size_t l = 1; l <= options.coarseSources.size(); ++l)
        if (SliceReader* s = coarseSource(l);
            !s || l >= levels.size() || !options.externalRecord || s->info().dims != levels[l].volume.dims ||
            s->info().type != info.type)
            throw std::logic_error("store writer: a coarse source that is not its level's");

    const StoreResume* resume = options.resume;
    const StoreCheckpoint* from = resume ? resume->from : nullptr;
    const std::string identity = resume ? storeResumeIdentity(source.info(), source.name(), options, resume->sourceIdentity) : "";
    if (from && from->identity != identity)
        throw std::logic_error("store writer: a checkpoint of another conversion to go on from");
    const auto out = resume ? std::make_unique<AtomicOutputFile>(outPath, options.overwrite, source.files(),
                                                                 resume->partialPath, from != nullptr)
                            : std::make_unique<AtomicOutputFile>(outPath, options.overwrite, source.files());
    uint64_t fileEnd = kStoreHeaderBytes;  // the header is written last, at offset 0

    // Level 0 holds 2B+3 slices: a layer's B+3 and B more that the reader fills meanwhile; each
    // coarser level the B+3 of its layer.
    const MappedSlices ring(info.dims, sampleBytes, 2 * int64_t(B) + kGhostBefore + kGhostAfter, source.name());
    std::vector<LevelInProgress> coarse(size_t(levelCount - 1));
    for (size_t l = 0; l < coarse.size(); ++l) {
        coarse[l].level = levels[l + 1];
        coarse[l].ring = std::make_unique<MappedSlices>(coarse[l].level.volume.dims, sampleBytes,
                                                        int64_t(B) + kGhostBefore + kGhostAfter, source.name());
    }

    const int64_t totalBricks = levels.back().firstBrick + levels.back().layout.brickCount();
    std::vector<BrickEntry> entries(static_cast<size_t>(totalBricks));
    std::vector<SubBlockCode> subBlocks(entries.size() * kSubBlocksPerBrick);
    BrickEncoder encoder(info.type, options);
    BrickGroupWriter writer(out->fd(), out->path());

    // Encodes and writes layer `bk` of level l, its slices in `window`, a group of rows at a
    // time, each written in the order made while the next is encoded.
    auto emitLayer = [&](const SliceWindow& window, size_t l, int64_t bk) {
        const BrickLevel& level = levels[l];
        // An index's level 0, and the levels read from its own scales, are measured only.
        const bool external = options.externalRecord && (l == 0 || coarseSource(l));
        const BrickLayout& lay = level.layout;
        const int64_t rowBricks = lay.brickCounts[0];
        const int64_t groupRows = brickRowsPerGroup(lay);
        for (int64_t bj = 0; bj < lay.brickCounts[1]; bj += groupRows) {
            std::vector<EncodedBrick>& group = writer.group();
            const int64_t firstId = lay.brickId(0, bj, bk);
            const int64_t count = std::min(groupRows, lay.brickCounts[1] - bj) * rowBricks;
            encoder.encode(window, lay, firstId, count, l == 0, external, group);
            const uint64_t groupStart = fileEnd;
            fileEnd = placeBricks(group, count, groupStart);
            for (int64_t b = 0; b < count; ++b) {
                const EncodedBrick& eb = group[size_t(b)];
                const int64_t id = level.firstBrick + firstId + b;
                entries[size_t(id)] = eb.entry;
                std::copy(std::begin(eb.subBlocks), std::end(eb.subBlocks),
                          subBlocks.begin() + id * kSubBlocksPerBrick);
            }
            writer.write(count, groupStart, fileEnd);
        }
    };

    // Level `l` (>= 1) makes every slice it can now that the level below holds slices up to
    // `below`; each new slice goes on to the next level, and each layer it completes is encoded.
    std::function<void(size_t, int64_t)> feed = [&](size_t l, int64_t below) {
        LevelInProgress& level = coarse[l - 1];
        const SliceWindow fineWindow = l == 1 ? ring.window() : coarse[l - 2].ring->window();
        const Dims3& fine = levels[l - 1].volume.dims;
        const Dims3& dims = level.level.volume.dims;
        const SliceWindow window = level.ring->window();
        while (level.nextSlice < dims[2] &&
               (2 * level.nextSlice + 1 <= below || below == fine[2] - 1)) {
            const int64_t z = level.nextSlice;
            if (SliceReader* own = coarseSource(l)) own->read(window.slice(z), 1);
            else downsampleSlice(info.type, fineWindow, fine, dims, z, window.slice(z));
            ++level.nextSlice;
            if (l < coarse.size()) feed(l + 1, z);
            const BrickLayout& lay = level.level.layout;
            // (Two layers can end on the volume's last slice.)
            while (level.nextLayer < lay.brickCounts[2] && lastSliceOfLayer(lay, level.nextLayer) == z)
                emitLayer(window, l, level.nextLayer++);
        }
    };

    // Where an earlier run stopped (StoreResume::from): what it made, and its coarse levels'
    // slices; level 0 reads again the slices of the layer it goes on with.
    int64_t firstLayer = 0, fedSlices = 0;  // fedSlices: level-0 slices handed to level 1
    std::vector<uint64_t> fineBefore(size_t(kFineHistogramBins), 0);
    if (from) {
        bool fits = from->entries.size() == entries.size() && from->subBlocks.size() == subBlocks.size() &&
                    from->fineHistogram.size() == fineBefore.size() && from->levels.size() == coarse.size() &&
                    from->nextLayer > 0 && from->nextLayer < layout.brickCounts[2] && from->fileEnd >= fileEnd;
        for (size_t l = 0; fits && l < coarse.size(); ++l) {
            const SliceWindow w = coarse[l].ring->window();
            fits = from->levels[l].ring.size() == w.sliceBytes * size_t(w.slots);
        }
        if (!fits) throwIoError(resume->checkpointPath, "does not fit the conversion it names; run again with --restart");
        if (out->size() < from->fileEnd)
            throwIoError(resume->partialPath, "is shorter than its checkpoint says; run again with --restart");
        entries = from->entries;
        subBlocks = from->subBlocks;
        fineBefore = from->fineHistogram;
        fileEnd = from->fileEnd;
        fedSlices = from->fedSlices;
        firstLayer = from->nextLayer;
        for (size_t l = 0; l < coarse.size(); ++l) {
            coarse[l].nextSlice = from->levels[l].nextSlice;
            coarse[l].nextLayer = from->levels[l].nextLayer;
            std::copy(from->levels[l].ring.begin(), from->levels[l].ring.end(), coarse[l].ring->window().bytes);
            if (SliceReader* own = coarseSource(l + 1)) own->skip(coarse[l].nextSlice);
        }
        out->truncate(fileEnd);
    }

    // Level 0's samples counted so far, by earlier runs too.
    auto fineHistogram = [&] {
        std::vector<uint64_t> fine = encoder.fineHistogram();
        for (size_t i = 0; i < fine.size(); ++i) fine[i] += fineBefore[i];
        return fine;
    };

    // Saves where the run stands before level 0's layer `bk`, its slices read (StoreResume).
    auto lastSave = Clock::now();
    double saveSeconds = 0;
    auto saveCheckpoint = [&](int64_t bk) {
        const auto t0 = Clock::now();
        writer.finish();
        out->truncate(fileEnd);  // the bricks' end, though the last bytes are alignment or the header's place
        out->flush();
        StoreCheckpoint c;
        c.identity = identity;
        c.nextLayer = bk;
        c.fedSlices = fedSlices;
        c.fileEnd = fileEnd;
        c.entries = entries;
        c.subBlocks = subBlocks;
        c.fineHistogram = fineHistogram();
        std::vector<CheckpointRing> rings;
        for (const LevelInProgress& level : coarse) {
            c.levels.push_back({level.nextSlice, level.nextLayer, {}});
            const SliceWindow w = level.ring->window();
            rings.push_back({w.bytes, w.sliceBytes * size_t(w.slots)});
        }
        if (resume->sourceState) {
            std::vector<int64_t> slicesRead{lastSliceOfLayer(layout, bk) + 1};
            for (const LevelInProgress& level : coarse) slicesRead.push_back(level.nextSlice);
            c.source = resume->sourceState(slicesRead);
        }
        writeStoreCheckpoint(resume->checkpointPath, c, rings);
        out->keepOnFailure();  // the checkpoint goes on from the partial file
        lastSave = Clock::now();
        saveSeconds = secondsSince(t0);
    };

    const SliceWindow window = ring.window();
    const int64_t firstSlice = std::max<int64_t>(0, layout.firstSample(firstLayer));
    source.skip(firstSlice);
    readSlices(source, window, firstSlice, lastSliceOfLayer(layout, firstLayer) + 1);
    for (int64_t bk = firstLayer; bk < layout.brickCounts[2]; ++bk) {
        throwIfInterrupted(source.name());  // also without a progress callback
        if (resume && bk > firstLayer && secondsSince(lastSave) >= std::max(resume->everySeconds, 10 * saveSeconds))
            saveCheckpoint(bk);
        std::future<void> prefetch;
        if (bk + 1 < layout.brickCounts[2])
            prefetch = std::async(std::launch::async, readSlices, std::ref(source), window,
                                  lastSliceOfLayer(layout, bk) + 1, lastSliceOfLayer(layout, bk + 1) + 1);
        emitLayer(window, 0, bk);
        // The slices the next layer does not read again are final for level 1 now; the reader
        // fills other slots meanwhile.
        if (!coarse.empty()) {
            const int64_t last = lastSliceOfLayer(layout, bk);
            for (; fedSlices <= last; ++fedSlices) feed(1, fedSlices);
        }
        if (prefetch.valid()) prefetch.get();
        if (progress) progress(double(bk + 1) / double(layout.brickCounts[2]));
    }
    writer.finish();
    for (const LevelInProgress& level : coarse)
        if (level.nextLayer != level.level.layout.brickCounts[2])
            throw std::logic_error("store writer: a level of detail was not completed");
    source.finish();
    for (SliceReader* own : options.coarseSources) own->finish();

    uint64_t externalOffset = 0;
    std::vector<unsigned char> external;
    if (options.externalRecord) {
        external = options.externalRecord();
        externalOffset = fileEnd;
        out->writeAt(external.data(), external.size(), fileEnd);
        fileEnd += external.size();
    }
    StoreTail tail = finishStore(info, options, levelCount, layout.brickCount(), entries, subBlocks, fineHistogram(),
                                 fileEnd, source.name());
    if (!external.empty()) {
        tail.header.externalOffset = externalOffset;
        tail.header.externalBytes = external.size();
        tail.header.externalLevels = 1 + int(options.coarseSources.size());
        tail.headerBytes = store_format::encodeHeader(tail.header);
    }
    out->writeAt(tail.index.data(), tail.index.size(), fileEnd);
    out->writeAt(tail.headerBytes.data(), tail.headerBytes.size(), 0);
    out->commit();
    if (resume) ::unlink(resume->checkpointPath.c_str());  // done: nothing to go on from

    StoreWriteSummary summary;
    summary.bricks = totalBricks;
    summary.levels = levelCount;
    summary.level0Bytes = tail.level0Bytes;
    summary.coarseBytes = tail.header.storedBrickBytes - tail.level0Bytes;
    summary.inputBytes = info.byteSize();
    summary.fileBytes = fileEnd + tail.index.size();
    summary.seconds = secondsSince(start);
    summary.layers = layout.brickCounts[2];
    summary.resumedLayers = firstLayer;
    return summary;
}

}  // namespace vdiso
