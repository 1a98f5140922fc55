// The levels of an index (vdiso index) that lie in the Zarr arrays it indexes (level 0, and an
// OME-Zarr's own scales as coarser levels), their bricks assembled from those arrays: each
// brick's (B+3)^3 samples, clamped at the volume's faces as the store writer gathers them
// (a scale one or two samples short of its level's dims is clamped at its own last sample,
// as the index read it: io/readers/edge_padded_reader.h), copied from the chunks that hold
// them (any chunk shape), through one cache of decoded chunks so that bricks sharing a chunk
// fetch and decode it once; a brick's chunks not held are fetched together (at a URL in
// parallel, a shard's neighbouring inner chunks in one range). Every chunk is checked against its pin as it is read: a chunk
// whose bytes changed since indexing is refused, naming it.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "core/brick_layout.h"
#include "io/remote/remote_options.h"
#include "io/store/external_level.h"
#include "io/store/store_format.h"

namespace vdiso {

class ExternalBricks {
public:
    // Opens the arrays `records` name, the store's levels 0, 1, ... (their locations taken
    // from `indexPath`'s folder when relative). Throws IoError when one cannot be opened or is
    // not the array indexed: another shape, sample type, chunk grid, spacing or origin, or
    // metadata changed since; or when the records are not the header's external levels.
    ExternalBricks(const std::string& indexPath, const StoreHeader& header, std::vector<ExternalLevel> records,
                   const RemoteOptions& remote, size_t cacheBytes);
    ~ExternalBricks();

    // Level 0's array's name as messages show it.
    const std::string& name() const;
    // Levels that lie in the arrays (1: level 0 only).
    int levelCount() const;

    // Brick `id`'s (B+3)^3 samples into dst (numbered through all levels, of a level that lies
    // in an array). Safe from several threads. Throws IoError naming the chunk when it cannot be
    // read or decoded, or changed since indexing.
    void assemble(int64_t id, unsigned char* dst) const;

    // Chunks fetched and decoded so far, of every level; bytes of them as stored.
    uint64_t chunksRead() const;
    uint64_t chunkBytesRead() const;
    // Whether the array is at a URL; its requests and the bytes they brought (0 for a folder).
    bool isRemote() const;
    uint64_t requests() const;
    uint64_t bytesFetched() const;

private:
    struct Impl;
    std::unique_ptr<Impl> mImpl;
};

}  // namespace vdiso
