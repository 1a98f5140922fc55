#include "io/store/zarr_index.h"

#include <cstring>
#include <filesystem>
#include <optional>
#include <sstream>

#include "core/settings_error.h"
#include "io/error.h"
#include "io/readers/zarr_reader.h"
#include "io/remote/remote_file.h"
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

// A checkpoint's source state: the chunk layers read so far, then the record with their
// chunks' pins (io/store/external_level.h; the others not read yet).
//   u64 layers, [external record]
std::vector<unsigned char> encodePinnedLayers(const ExternalLevel& record, int64_t layers) {
    std::vector<unsigned char> out(8);
    const uint64_t n = uint64_t(layers);
    std::memcpy(out.data(), &n, 8);
    const std::vector<unsigned char> pins = encodeExternalLevel(record);
    out.insert(out.end(), pins.begin(), pins.end());
    return out;
}

// Puts the pins back into `record`; returns the layers they cover. Throws IoError naming
// `checkpointPath` when they do not fit the array.
int64_t decodePinnedLayers(const std::vector<unsigned char>& bytes, ExternalLevel& record,
                           const std::string& checkpointPath) {
    uint64_t layers = ~uint64_t(0);
    if (bytes.size() >= 8) std::memcpy(&layers, bytes.data(), 8);
    if (layers > uint64_t(record.chunkCounts[2]))
        throwIoError(checkpointPath, "holds pins that do not fit the array; run again with --restart");
    ExternalLevel saved = decodeExternalLevel(bytes.data() + 8, bytes.size() - 8, checkpointPath);
    if (saved.pins.size() != record.pins.size())
        throwIoError(checkpointPath, "holds pins that do not fit the array; run again with --restart");
    record.pins = std::move(saved.pins);
    return int64_t(layers);
}

}  // namespace

ZarrIndexSummary indexZarr(const std::string& dataPath, const std::string& indexPath, const ZarrIndexOptions& options,
                           const ProgressFn& progress) {
    auto volume = std::make_unique<ZarrVolume>(dataPath, options.level, options.remote);
    ExternalLevel record;
    record.location = externalLocationFor(dataPath, indexPath);
    record.level = options.level;
    record.metadataCrc = volume->metadataCrc();
    record.chunkShape = volume->chunkShape();
    record.chunkCounts = volume->chunkCounts();
    record.pins.assign(size_t(volume->chunkCount()), ZarrChunkPin{});

    // An earlier run's checkpoint of this array, these options, and its partial index: go on.
    StoreResume resume;
    resume.partialPath = indexPartialPath(indexPath);
    resume.checkpointPath = indexCheckpointPath(indexPath);
    resume.everySeconds = options.checkpointSeconds;
    std::ostringstream source;
    source << "zarr " << record.location << " level " << record.level << " metadata " << record.metadataCrc
           << " chunks " << record.chunkShape[0] << ' ' << record.chunkShape[1] << ' ' << record.chunkShape[2];
    resume.sourceIdentity = source.str();
    const int64_t depth = record.chunkShape[2];
    resume.sourceState = [&record, depth](int64_t slicesRead) {
        return encodePinnedLayers(record, (slicesRead + depth - 1) / depth);
    };
    StoreWriteOptions store = options.store;
    store.externalRecord = [&] { return encodeExternalLevel(record); };
    store.resume = &resume;
    ZarrIndexSummary summary;
    std::optional<StoreCheckpoint> checkpoint;
    if (options.restart) std::filesystem::remove(resume.checkpointPath);
    else checkpoint = readStoreCheckpoint(resume.checkpointPath);
    int64_t pinnedLayers = 0;
    if (checkpoint) {
        std::error_code error;
        const auto partialBytes = std::filesystem::file_size(resume.partialPath, error);
        if (checkpoint->identity != storeResumeIdentity(volume->info(), volume->name(), store, resume.sourceIdentity))
            summary.startedOver = "the interrupted run indexed another array, or with other options";
        else if (error || partialBytes < checkpoint->fileEnd)
            summary.startedOver = resume.partialPath + " is missing or shorter than the checkpoint says";
        else {
            pinnedLayers = decodePinnedLayers(checkpoint->source, record, resume.checkpointPath);
            resume.from = &*checkpoint;
        }
        // Starting over writes the partial index afresh: its old checkpoint would no longer fit.
        if (!resume.from) std::filesystem::remove(resume.checkpointPath);
    }
    const auto reader = zarrSliceReader(std::move(volume), &record.pins, pinnedLayers);
    summary.store = writeBrickStore(*reader, indexPath, store, progress);
    summary.chunks = int64_t(record.pins.size());
    for (const ZarrChunkPin& pin : record.pins) {
        if (pin.bytes == ZarrChunkPin::kMissing) ++summary.missingChunks;
        else summary.dataBytes += pin.bytes;
    }
    return summary;
}

}  // namespace vdiso
