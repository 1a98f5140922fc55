#include "io/store/zarr_index.h"

#include <cmath>
#include <cstring>
#include <filesystem>
#include <optional>
#include <sstream>

#include "core/brick_levels.h"
#include "core/settings_error.h"
#include "io/error.h"
#include "io/readers/edge_padded_reader.h"
#include "io/readers/zarr_reader.h"
#include "io/remote/remote_file.h"
#include "io/store/brick_encoder.h"
#include "io/store/external_level.h"
#include "io/store/store_checkpoint.h"

namespace vdiso {

std::string indexPathFor(const std::string& dataPath, const std::string& indexPath) {
    if (isRemoteLocation(indexPath))
        throw SettingsError("index", "expects a local file: an index is written here, then read from anywhere");
    if (!indexPath.empty()) return indexPath;
    if (isRemoteLocation(dataPath))
        throw SettingsError("index", "expects the index's path: data at a URL has no folder beside it here");
    return defaultIndexPath(dataPath);
}

std::string indexPartialPath(const std::string& indexPath) { return indexPath + ".partial"; }
std::string indexCheckpointPath(const std::string& indexPath) { return indexPath + ".resume"; }

namespace {

// A level read from the array: its record (pins filled as its chunks are read) and its depth
// in samples (the array's own, which a coarse scale's may be short of its level's).
struct IndexedLevel {
    ExternalLevel record;
    std::unique_ptr<ZarrVolume> volume;
    int64_t arrayDepth = 0;
    int64_t pinnedLayers = 0;  // layers of chunks an interrupted run read
};

// A checkpoint's source state: for each level read from the array, the chunk layers read so
// far, then its record with their chunks' pins (io/store/external_level.h; the others not
// read yet).
//   u32 levels, levels x (u64 layers, u64 recordBytes, [record])
std::vector<unsigned char> encodePinnedLayers(const std::vector<IndexedLevel>& levels,
                                              const std::vector<int64_t>& slicesRead) {
    std::vector<unsigned char> out(4);
    const uint32_t count = uint32_t(levels.size());
    std::memcpy(out.data(), &count, 4);
    for (size_t l = 0; l < levels.size(); ++l) {
        const int64_t depth = levels[l].record.chunkShape[2];
        const int64_t read = std::min(slicesRead.at(l), levels[l].arrayDepth);
        const uint64_t layers = uint64_t((read + depth - 1) / depth);
        const std::vector<unsigned char> pins = encodeExternalLevels({levels[l].record});
        const uint64_t bytes = pins.size();
        const size_t at = out.size();
        out.resize(at + 16);
        std::memcpy(out.data() + at, &layers, 8);
        std::memcpy(out.data() + at + 8, &bytes, 8);
        out.insert(out.end(), pins.begin(), pins.end());
    }
    return out;
}

// Puts the pins back into `levels`' records and their layers into pinnedLayers. Throws
// IoError naming `checkpointPath` when they do not fit the arrays.
void decodePinnedLayers(const std::vector<unsigned char>& bytes, std::vector<IndexedLevel>& levels,
                        const std::string& checkpointPath) {
    auto unfit = [&] { throwIoError(checkpointPath, "holds pins that do not fit the array; run again with --restart"); };
    uint32_t count = 0;
    if (bytes.size() >= 4) std::memcpy(&count, bytes.data(), 4);
    if (count != levels.size()) unfit();
    size_t at = 4;
    for (IndexedLevel& level : levels) {
        uint64_t layers = 0, n = 0;
        if (bytes.size() - at < 16) unfit();
        std::memcpy(&layers, bytes.data() + at, 8);
        std::memcpy(&n, bytes.data() + at + 8, 8);
        at += 16;
        if (layers > uint64_t(level.record.chunkCounts[2]) || n > bytes.size() - at) unfit();
        std::vector<ExternalLevel> saved = decodeExternalLevels(bytes.data() + at, size_t(n), checkpointPath);
        at += size_t(n);
        if (saved.size() != 1 || saved[0].pins.size() != level.record.pins.size()) unfit();
        level.record.pins = std::move(saved[0].pins);
        level.pinnedLayers = int64_t(layers);
    }
}

// The OME-Zarr scales after `level0`'s that stand for the store's levels 1, 2, ... (at most
// `most`), opened: scale `level0 + l` is level l when its spacing is 2^l times level 0's on x, y
// and z, its origin level 0's (vdiso's coarse sample s stands at level-0 sample s 2^l), its
// samples of level 0's type, and it is at most kScaleSamplesShort samples short of the level's
// dims on each axis (core/brick_levels.h levelDims). The first that is not ends them; `why` says why.
std::vector<std::unique_ptr<ZarrVolume>> ownScales(const std::string& dataPath, const ZarrVolume& level0, int first,
                                                   int most, const RemoteOptions& remote, std::string& why) {
    std::vector<std::unique_ptr<ZarrVolume>> scales;
    const VolumeInfo& v0 = level0.info();
    for (int l = 1; l <= most && first + l < level0.levelCount(); ++l) {
        auto scale = std::make_unique<ZarrVolume>(dataPath, first + l, remote);
        const VolumeInfo& v = scale->info();
        const double factor = double(int64_t(1) << l);
        const Dims3 want = levelDims(v0.dims, l);
        std::string problem;
        for (int a = 0; a < 3 && problem.empty(); ++a) {
            if (std::abs(v.spacing[a] / v0.spacing[a] - factor) > 1e-6 * factor)
                problem = "its spacing is not " + std::to_string(int64_t(factor)) + " times level " + std::to_string(first) + "'s on every axis";
            else if (std::abs(v.origin[a] - v0.origin[a]) > 1e-6 * v0.spacing[a])
                problem = "its origin is not level " + std::to_string(first) + "'s (its samples stand between vdiso's)";
            else if (v.dims[a] > want[a] || v.dims[a] < want[a] - kScaleSamplesShort)
                problem = "its shape is not that of a level of " + std::to_string(int64_t(factor)) + "x cells";
        }
        if (problem.empty() && v.type != v0.type) problem = "its samples are of another type";
        if (!problem.empty()) {
            why = "scale " + std::to_string(first + l) + " is not used: " + problem;
            break;
        }
        scales.push_back(std::move(scale));
    }
    return scales;
}

}  // namespace

ZarrIndexSummary indexZarr(const std::string& dataPath, const std::string& indexPath, const ZarrIndexOptions& options,
                           const ProgressFn& progress) {
    std::vector<IndexedLevel> levels(1);
    levels[0].volume = std::make_unique<ZarrVolume>(dataPath, options.level, options.remote);
    ZarrIndexSummary summary;
    const VolumeInfo info = storeVolumeFor(levels[0].volume->info(), options.store, levels[0].volume->name());
    const int levelCount = storeLevelCount(BrickLayout(info.dims, options.store.brickSize), options.store);
    if (options.scaleLevels > 0 && levelCount > 1)
        for (auto& scale : ownScales(dataPath, *levels[0].volume, options.level,
                                     std::min(levelCount - 1, options.scaleLevels), options.remote,
                                       summary.scalesNotUsed))
            levels.push_back(IndexedLevel{{}, std::move(scale)});
    const std::string location = externalLocationFor(dataPath, indexPath);
    for (size_t l = 0; l < levels.size(); ++l) {
        IndexedLevel& level = levels[l];
        ExternalLevel& record = level.record;
        record.location = location;
        record.level = options.level + int(l);
        record.metadataCrc = level.volume->metadataCrc();
        record.chunkShape = level.volume->chunkShape();
        record.chunkCounts = level.volume->chunkCounts();
        record.pins.assign(size_t(level.volume->chunkCount()), ZarrChunkPin{});
        level.arrayDepth = level.volume->info().dims[2];
    }

    // An earlier run's checkpoint of this array, these options, and its partial index: go on.
    StoreResume resume;
    resume.partialPath = indexPartialPath(indexPath);
    resume.checkpointPath = indexCheckpointPath(indexPath);
    resume.everySeconds = options.checkpointSeconds;
    std::ostringstream source;
    source << "zarr " << location;
    for (const IndexedLevel& level : levels) {
        const ExternalLevel& r = level.record;
        source << " level " << r.level << " metadata " << r.metadataCrc << " chunks " << r.chunkShape[0] << ' '
               << r.chunkShape[1] << ' ' << r.chunkShape[2];
    }
    resume.sourceIdentity = source.str();
    resume.sourceState = [&levels](const std::vector<int64_t>& slicesRead) {
        return encodePinnedLayers(levels, slicesRead);
    };
    StoreWriteOptions store = options.store;
    store.externalRecord = [&] {
        std::vector<ExternalLevel> records;
        for (const IndexedLevel& level : levels) records.push_back(level.record);
        return encodeExternalLevels(records);
    };
    store.resume = &resume;
    std::optional<StoreCheckpoint> checkpoint;
    if (options.restart) std::filesystem::remove(resume.checkpointPath);
    else checkpoint = readStoreCheckpoint(resume.checkpointPath);
    std::vector<std::unique_ptr<SliceReader>> coarse;  // the scales' readers, as their levels' dims
    if (checkpoint) {
        std::error_code error;
        const auto partialBytes = std::filesystem::file_size(resume.partialPath, error);
        const std::string identity = storeResumeIdentity(levels[0].volume->info(), levels[0].volume->name(), store,
                                                         resume.sourceIdentity);
        if (checkpoint->identity != identity)
            summary.startedOver = "the interrupted run indexed another array, or with other options";
        else if (error || partialBytes < checkpoint->fileEnd)
            summary.startedOver = resume.partialPath + " is missing or shorter than the checkpoint says";
        else {
            decodePinnedLayers(checkpoint->source, levels, resume.checkpointPath);
            resume.from = &*checkpoint;
        }
        // Starting over writes the partial index afresh: its old checkpoint would no longer fit.
        if (!resume.from) std::filesystem::remove(resume.checkpointPath);
    }
    for (size_t l = 1; l < levels.size(); ++l) {
        const Dims3 dims = levelDims(info.dims, int(l));
        coarse.push_back(edgePaddedReader(
            zarrSliceReader(std::move(levels[l].volume), &levels[l].record.pins, levels[l].pinnedLayers), dims));
        store.coarseSources.push_back(coarse.back().get());
    }
    const auto reader = zarrSliceReader(std::move(levels[0].volume), &levels[0].record.pins, levels[0].pinnedLayers);
    summary.store = writeBrickStore(*reader, indexPath, store, progress);
    summary.ownScaleLevels = int(levels.size()) - 1;
    for (const IndexedLevel& level : levels)
        for (const ZarrChunkPin& pin : level.record.pins) {
            ++summary.chunks;
            if (pin.bytes == ZarrChunkPin::kMissing) ++summary.missingChunks;
            else summary.dataBytes += pin.bytes;
        }
    return summary;
}

}  // namespace vdiso
