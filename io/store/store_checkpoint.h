// Where a resumable store writer stood (io/store/store_writer.h, StoreResume; vdiso index): what
// it had made when level 0's layer `nextLayer` was next, so that a run that failed, was
// interrupted or killed goes on from there instead of reading everything again.
//
//   "VDISOCKP" u32 version (2) u32 identityBytes [identity] i64 nextLayer i64 fedSlices
//   u64 fileEnd u64 entries [each as the store's index holds it: store_format::encodeEntry]
//   u64 subBlocks [each: u8 lo u8 hi] u64 bins [u64 count each] u32 levels [each:
//   i64 nextSlice i64 nextLayer u64 ringBytes [ring]] u64 sourceBytes [source] u32 CRC-32
//
// The file is the writer's scratch beside its partial output, read back by the same program:
// it is no format to exchange. The identity says what was being written (the volume, the
// options, the caller's source); a checkpoint of anything else is not resumed.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "core/brick_source.h"
#include "io/store/store_format.h"

namespace vdiso {

struct StoreCheckpoint {
    std::string identity;
    int64_t nextLayer = 0;            // level 0's next layer of bricks
    int64_t fedSlices = 0;            // level-0 slices handed to level 1 so far
    uint64_t fileEnd = 0;             // the partial output's bytes that count
    std::vector<BrickEntry> entries;  // every level's, those not made yet zero
    std::vector<SubBlockCode> subBlocks;
    std::vector<uint64_t> fineHistogram;  // level 0's samples counted so far
    // Each coarser level in progress: its next slice and layer, and its ring of slices whole.
    struct Level {
        int64_t nextSlice = 0, nextLayer = 0;
        std::vector<unsigned char> ring;
    };
    std::vector<Level> levels;
    std::vector<unsigned char> source;  // the caller's (io/store/store_writer.h StoreResume)
};

// Writes `checkpoint` at `path` whole or not at all (io/atomic_output.h), replacing the one
// there. `rings[l]` (levels[l].ring's size in ringBytes[l]) stand in for the levels' rings,
// which are written from where they lie. Throws IoError naming `path`.
struct CheckpointRing {
    const unsigned char* bytes;
    size_t size;
};
void writeStoreCheckpoint(const std::string& path, const StoreCheckpoint& checkpoint,
                          const std::vector<CheckpointRing>& rings);

// The checkpoint at `path`; nullopt when there is none. Throws IoError naming `path` when it
// cannot be read or is damaged.
std::optional<StoreCheckpoint> readStoreCheckpoint(const std::string& path);

}  // namespace vdiso
