// Level 0 of an index (vdiso index) assembled from the Zarr array it indexes: each brick's
// (B+3)^3 samples, clamped at the volume's faces as the store writer gathers them, copied
// from the chunks that hold them (any chunk shape), through a cache of decoded chunks so that
// bricks sharing a chunk fetch and decode it once. Every chunk is checked against its pin as
// it is read: a chunk whose bytes changed since indexing is refused, naming it.
#pragma once

#include <cstdint>
#include <memory>
#include <string>

#include "core/brick_layout.h"
#include "io/remote/remote_options.h"
#include "io/store/external_level.h"
#include "io/store/store_format.h"

namespace vdiso {

class ExternalBricks {
public:
    // Opens the array `record` names (its location taken from `indexPath`'s folder when
    // relative). Throws IoError when it cannot be opened or is not the array indexed: another
    // shape, sample type, chunk grid, spacing or origin, or metadata changed since.
    ExternalBricks(const std::string& indexPath, const StoreHeader& header, ExternalLevel record,
                   const RemoteOptions& remote, size_t cacheBytes);
    ~ExternalBricks();

    // The array's name as messages show it.
    const std::string& name() const;

    // Level-0 brick `id`'s (B+3)^3 samples into dst. Safe from several threads. Throws IoError
    // naming the chunk when it cannot be read or decoded, or changed since indexing.
    void assemble(int64_t id, unsigned char* dst) const;

    // Chunks fetched and decoded so far; bytes of them as stored.
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
