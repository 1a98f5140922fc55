// vdiso index: an index of a Zarr array (plain, or an OME-Zarr image's level) where it lies,
// so that every front end opens the array like a store without converting it
// (io/store/brick_store.h). The array is read once, a layer of chunks at a time (the store
// writer's pass, io/store/store_writer.h), and the index holds what a store's index holds (each
// brick's range, sub-block codes, the histogram) and the coarser levels of detail as a store
// has them, but not level 0's samples: instead, where the array is and each chunk's pin
// (io/store/external_level.h), so that a changed chunk is refused when read.
#pragma once

#include <cstdint>
#include <string>

#include "core/progress.h"
#include "io/remote/remote_options.h"
#include "io/store/store_writer.h"

namespace vdiso {

struct ZarrIndexOptions {
    int level = 0;           // the OME-Zarr multiscale level indexed (0, the finest)
    StoreWriteOptions store;  // brick size, levels of detail, their compression, overwrite
    RemoteOptions remote;
    // Resuming: the index is written as INDEX.partial, with where the pass stands saved as
    // INDEX.resume (io/store/store_checkpoint.h) at least this many seconds apart; a run that
    // finds both goes on from there (unless `restart`), provided it indexes the same array
    // with the same options.
    double checkpointSeconds = 30;
    bool restart = false;
};

struct ZarrIndexSummary {
    StoreWriteSummary store;   // fileBytes: the index's size; resumedLayers: from an earlier run
    int64_t chunks = 0, missingChunks = 0;
    uint64_t dataBytes = 0;    // the array's chunks as stored
    // Why a checkpoint found was not gone on from (empty if none was found, or it was).
    std::string startedOver;
};

// Where the index of `dataPath` goes: `indexPath` when given, else beside local data
// (DATA.vdiso, io/store/external_level.h). Throws SettingsError("index", ...) for data at a URL
// without an index path, and for an index path that is a URL (an index is written locally).
std::string indexPathFor(const std::string& dataPath, const std::string& indexPath);

// Where an index at `indexPath` is written until done (INDEX.partial), and where the pass's
// checkpoint is kept (INDEX.resume).
std::string indexPartialPath(const std::string& indexPath);
std::string indexCheckpointPath(const std::string& indexPath);

// Indexes the array at `dataPath` (a folder or URL) into `indexPath` (a local file). Throws as
// writeBrickStore does (no index left, an existing one untouched), but leaves INDEX.partial
// and INDEX.resume for the next run to go on from; both go once the index is written. Throws
// IoError naming the chunk when a chunk an interrupted run read has changed since.
ZarrIndexSummary indexZarr(const std::string& dataPath, const std::string& indexPath, const ZarrIndexOptions& options,
                           const ProgressFn& progress = {});

}  // namespace vdiso
