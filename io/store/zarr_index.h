// vdiso index: an index of a Zarr array (plain, or an OME-Zarr image's level) where it lies,
// so that every front end opens the array like a store without converting it
// (io/store/brick_store.h). The array is read once, a layer of chunks at a time (the store
// writer's pass, io/store/store_writer.h), and the index holds what a store's index holds (each
// brick's range, sub-block codes, the histogram), but not level 0's samples: instead, where the
// array is and each chunk's pin (io/store/external_level.h), so that a changed chunk is refused
// when read. An OME-Zarr's own coarser scales stand for the first coarser levels of detail
// (ZarrIndexOptions::scaleLevels of them, one by default) where they fit them (2^l times level
// 0's spacing, its origin, the level's shape to within two samples): they are read once too, in
// step with level 0, measured and pinned like it, and their samples stay where they are; the
// levels past them are filtered from the last and stored in the index, as a store has them.
#pragma once

#include <cstdint>
#include <string>

#include "core/progress.h"
#include "io/remote/remote_options.h"
#include "io/store/store_writer.h"

namespace vdiso {

struct ZarrIndexOptions {
    int level = 0;           // the OME-Zarr multiscale level indexed (0, the finest)
    // How many coarser levels, at most, are taken from the OME-Zarr's own scales where they fit
    // (`--scale-levels`; 0: every coarser level filtered from level 0 and stored, `--own-levels`).
    // One by default: level 1 is an eighth of the data, and a coarser scale's chunks each cover
    // so much of the volume that a view from a bucket would fetch most of them whole (the
    // 2048^3 head's normal view: 61 of scale 2's 64 chunks, 146 MB).
    int scaleLevels = 1;
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
    int64_t chunks = 0, missingChunks = 0;  // of every scale read
    uint64_t dataBytes = 0;    // those chunks as stored
    // Why a checkpoint found was not gone on from (empty if none was found, or it was).
    std::string startedOver;
    int ownScaleLevels = 0;     // coarser levels taken from the OME-Zarr's own scales
    std::string scalesNotUsed;  // why the next scale was not taken (empty: none was left, or not asked)
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
