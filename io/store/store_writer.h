// Conversion into the brick store, streaming.
//
// Levels of detail (core/brick_levels.h) are made in the same pass: each level-0 slice, once
// its layer is encoded, is filtered into level 1 (core/lod/downsample.h), level 1's into level 2,
// and so on; each level holds B+3 slices of its own, and its layers of bricks are encoded and
// written as they complete, between level 0's. The input is read once.
//
// Holds 2B+3 z-slices: the B+3 a layer of bricks needs, and B more that a reader thread fills
// for the next layer while this one is encoded. Memory is those slices plus a few MB of
// compressed bricks, whatever the volume's depth. Bricks are gathered, measured (min, max,
// histogram) and compressed in parallel (TBB), a few rows at a time, and written in id order
// at 4 KiB-aligned offsets by a writer thread while the next rows are encoded, with writeback
// to disk started as they go. The header and index are
// written last and the file is renamed into place only when complete (AtomicOutputFile).
// The pieces (encoding, placing, the histogram, the header) are io/store/brick_encoder.h's, which the
// MPI converter (mpi/convert_across_ranks.h) shares, so both write the same store.
#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "core/progress.h"
#include "io/store/brick_store.h"
#include "io/readers/slice_reader.h"

namespace vdiso {

struct StoreCheckpoint;
struct StoreResume;

struct StoreWriteOptions {
    int brickSize = 32;                       // B, cells per brick side (2..512)
    Compression compression = Compression::Lz4;  // the faster first frame (io/store/brick_store.h)
    int compressionLevel = 1;                 // zstd level; 1 keeps conversion near disk speed
    bool shuffle = true;                      // byte-shuffle multi-byte samples before compressing
    bool overwrite = false;                   // replace an existing output file
    // Levels of detail beyond level 0; kLevelsUntilOneBrick: until the coarsest level is one
    // brick (`--levels auto`).
    static constexpr int kLevelsUntilOneBrick = -1;
    int coarseLevels = kLevelsUntilOneBrick;
    // An index (vdiso index, io/store/zarr_index.h): level 0's bricks are measured (ranges,
    // sub-block codes, histogram) but not stored, and this gives, once every slice is read,
    // the record of where they are (io/store/external_level.h), written into the file.
    std::function<std::vector<unsigned char>()> externalRecord;
    // An index of an OME-Zarr's own scales: level l's samples read from coarseSources[l - 1]
    // (the level's dims, core/brick_levels.h levelDims) instead of filtered from level l - 1,
    // its bricks measured and not stored like level 0's; levels past the end are filtered.
    // Each source is read once, in step with level 0. Needs externalRecord.
    std::vector<SliceReader*> coarseSources;
    // Resumable (vdiso index): StoreResume below. Null: the output is written unnamed.
    const StoreResume* resume = nullptr;
};

// A resumable conversion (vdiso index): the output is written under `partialPath`, and the
// writer's state is saved at `checkpointPath` (io/store/store_checkpoint.h) between level 0's
// layers, at least `everySeconds` apart and ten times as long apart as the last save took, so
// that saving costs a tenth of the run at most. A failure, an interrupt or a kill leaves both
// (a failure before the first checkpoint of a fresh run leaves neither); success removes the
// checkpoint. With `from`, the run goes on from that checkpoint, whose
// identity must be storeResumeIdentity's: the caller has put its source's state back (as
// `sourceState` saved it) and the writer skips the slices before the layer it resumes at.
struct StoreResume {
    std::string partialPath, checkpointPath;
    double everySeconds = 30;
    std::string sourceIdentity;  // what the source is (the caller's words)
    // The caller's state to save with a checkpoint: slicesRead[l], the slices of level l read
    // (level 0's from the source; a coarser level's from its coarse source, or made).
    std::function<std::vector<unsigned char>(const std::vector<int64_t>& slicesRead)> sourceState;
    const StoreCheckpoint* from = nullptr;
};

// The identity of a checkpoint that writing a source of `volume` (named `sourceName`) with
// `options` can go on from: the volume, the options that shape the output, `sourceIdentity`.
std::string storeResumeIdentity(const VolumeInfo& volume, const std::string& sourceName,
                                const StoreWriteOptions& options, const std::string& sourceIdentity);

struct StoreWriteSummary {
    int64_t bricks = 0;        // all levels
    int levels = 1;            // level 0 included
    uint64_t level0Bytes = 0;  // stored bytes of level 0's bricks
    uint64_t coarseBytes = 0;  // of the coarser levels' bricks
    uint64_t inputBytes = 0;   // samples read, at the store's sample size
    uint64_t fileBytes = 0;    // size of the written store
    double seconds = 0;
    int64_t layers = 0;         // level 0's layers of bricks
    int64_t resumedLayers = 0;  // of them, made by an earlier run (StoreResume::from)
};

// Converts everything `source` delivers into a store at `outPath`. Throws IoError (from the
// source or the output) or std::invalid_argument (bad options); on any throw, including one
// from `progress`, no output file is left and an existing one is untouched.
StoreWriteSummary writeBrickStore(SliceReader& source, const std::string& outPath,
                                  const StoreWriteOptions& options,
                                  const ProgressFn& progress = {});

}  // namespace vdiso
