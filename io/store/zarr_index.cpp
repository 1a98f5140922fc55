#include "io/store/zarr_index.h"

#include "core/settings_error.h"
#include "io/readers/zarr_reader.h"
#include "io/remote/remote_file.h"
#include "io/store/external_level.h"

namespace vdiso {

std::string indexPathFor(const std::string& dataPath, const std::string& indexPath) {
    if (isRemoteLocation(indexPath))
        throw SettingsError("index", "expects a local file: an index is written here, then read from anywhere");
    if (!indexPath.empty()) return indexPath;
    if (isRemoteLocation(dataPath))
        throw SettingsError("index", "expects the index's path: data at a URL has no folder beside it here");
    return defaultIndexPath(dataPath);
}

ZarrIndexSummary indexZarr(const std::string& dataPath, const std::string& indexPath, const ZarrIndexOptions& options,
                           const ProgressFn& progress) {
    auto volume = std::make_unique<ZarrVolume>(dataPath, options.level, options.remote);
    ExternalLevel record;
    record.location = externalLocationFor(dataPath, indexPath);
    record.level = options.level;
    record.metadataCrc = volume->metadataCrc();
    record.chunkShape = volume->chunkShape();
    record.chunkCounts = volume->chunkCounts();
    const auto reader = zarrSliceReader(std::move(volume), &record.pins);
    StoreWriteOptions store = options.store;
    store.externalRecord = [&] { return encodeExternalLevel(record); };
    ZarrIndexSummary summary;
    summary.store = writeBrickStore(*reader, indexPath, store, progress);
    summary.chunks = int64_t(record.pins.size());
    for (const ZarrChunkPin& pin : record.pins) {
        if (pin.bytes == ZarrChunkPin::kMissing) ++summary.missingChunks;
        else summary.dataBytes += pin.bytes;
    }
    return summary;
}

}  // namespace vdiso
