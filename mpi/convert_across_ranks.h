// Conversion into one brick store shared by the ranks of an mpirun job: the library side of
// `vdiso-mpi convert`. The store equals the one writeBrickStore (io/store/store_writer.h) makes from
// the same input, in every header field, brick, entry, sub-block code and histogram count; only
// where each brick lies in the file differs.
//
// Each rank opens the input itself (the same path on every node), skips to its slab
// (SliceReader::skip) and streams its run of level-0 layers of bricks as writeBrickStore does
// (a ring of 2B+3 slices, the next layer read while this one is encoded), reading only the
// three ghost slices at each border twice across neighbours (slab_partition.h says who owns
// what). Meanwhile it filters its own level-1 slices from its level-0 slices. Then, level by
// level, the ranks exchange the few slices at their borders that each other's layers and
// filters need (point to point), encode the layers whose first cell slice they own, and filter
// their own slices of the next level. Bricks are encoded by the functions writeBrickStore uses
// (io/store/brick_encoder.h).
//
// Writing: rank 0 refuses an existing output and creates a temporary file beside it
// (shared_output.h); every rank writes its compressed bricks into it, at offsets agreed in
// lockstep rounds: every rank encodes one group of brick rows per round (the same rows of a
// layer, or nothing when its run is shorter), one all-gather of the groups' 4 KiB-aligned sizes
// gives each its offset, and the writes go on a thread while the next group is encoded. The same
// all-gather carries failures: a rank that failed sends a mark instead of a size, and every rank
// leaves the conversion at that round. At the end rank 0 gathers the entries and sub-block
// codes, sums the ranks' histograms, writes the index and the header, and only when every rank
// has agreed it succeeded links the file into place.
//
// Memory per rank: the level-0 ring (2B+3 slices of the volume's x-y size; none on a rank
// without layers), two groups of compressed bricks (a few MB) and the encoder's per-thread
// scratch. The coarse levels' slices a rank holds (about 1/7 of its level-0 slab, plus a halo
// of B+3 slices per level) live in an unnamed file beside the output, mapped shared: the
// kernel writes them back under memory pressure, so one rank converts a volume larger than
// memory at the cost of that disk space.
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "core/volume.h"
#include "io/readers/slice_reader.h"
#include "io/store/store_writer.h"
#include "mpi/communicator.h"

namespace vdiso::mpi {

struct RanksConvertOptions {
    std::string output;          // the store to write
    StoreWriteOptions store;     // as writeBrickStore's; overwrite replaces an existing output
};

// One rank's share and what it cost.
struct RankConvertFigures {
    int64_t firstLayer = 0, layers = 0;  // its run of level-0 layers of bricks
    uint64_t slicesSkipped = 0;          // passed over to reach its slab (SliceReader::skip)
    uint64_t bytesRead = 0;              // slices read, at the store's sample size (ghosts included)
    uint64_t bricksWritten = 0;          // all levels
    uint64_t bytesWritten = 0;           // their stored bytes
    uint64_t haloBytesSent = 0;          // coarse-level slices sent to other ranks
    double seconds = 0;                  // from start to its part of the file written
};

struct RanksConvertResult {
    int ranks = 1;
    VolumeInfo volume;         // as stored
    std::string sourceName;    // rank 0's source's name()
    StoreWriteSummary summary; // totals, as writeBrickStore reports them (seconds: the job, on rank 0)
    std::vector<RankConvertFigures> perRank;  // rank 0 only: one per rank
};

// Opens the input on the calling rank; throws IoError naming the input.
using SliceReaderOpener = std::function<std::unique_ptr<SliceReader>()>;

// Collective. Throws RankFailure on every rank when any rank failed (exit code 2 for options
// that do not suit the volume, such as --levels beyond its count; 1 for the rest), naming the
// first failing rank and its error; no output is left then, and an existing one is untouched.
// A rank whose input differs from rank 0's (dimensions, type, placement) fails.
RanksConvertResult convertAcrossRanks(const Communicator& comm, const SliceReaderOpener& open,
                                      const RanksConvertOptions& options);

}  // namespace vdiso::mpi
