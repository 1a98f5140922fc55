// Zarr volumes from a directory store: a plain Zarr v2 or v3 array, or an OME-Zarr image
// (v0.4 on Zarr v2, v0.5 on Zarr v3) read at one level of its multiscales.
//
// The path is the array's folder (.zarray or zarr.json with node_type "array") or the image's
// group folder (.zattrs, or zarr.json with attributes.ome). For OME-Zarr, `level` picks
// multiscales[0].datasets[level] (0, the finest, by default); spacing and origin come from that
// dataset's "scale" and "translation" coordinate transformations, then the multiscale's own,
// on the three spatial axes (units are not converted). A plain array has spacing 1.
// The array's last three axes are z, y, x; any axes before them (OME-Zarr's t and c) must have
// size 1. Chunk formats: io/readers/zarr_array.h.
//
// Missing chunks are the fill value, as the Zarr specification says; a chunk that cannot be
// decoded is an error naming its file. Streaming: one layer of chunks (the chunk depth in z,
// across the whole slice) is decoded at a time, so memory is that layer whatever the depth; at
// a URL, the next layer's stored chunks are fetched meanwhile, and held too.
#pragma once

#include <cstdint>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include "io/readers/slice_reader.h"
#include "io/readers/zarr_keys.h"
#include "io/remote/remote_options.h"

namespace vdiso {

struct ZarrArrayMeta;

// What pins a chunk to the bytes indexed (vdiso index): its stored size and their CRC-32;
// a chunk that was not there (the fill value) has bytes == kMissing.
struct ZarrChunkPin {
    static constexpr uint64_t kMissing = ~uint64_t(0);
    uint64_t bytes = kMissing;
    uint32_t crc = 0;
    bool operator==(const ZarrChunkPin&) const = default;
};

// A Zarr volume's array, read a chunk at a time by its position in the chunk grid (x, y, z,
// the spatial axes; leading axes of size 1 are index 0). Safe to use from several threads.
// A sharded array's chunks are its inner chunks, read by ranges of their shard.
class ZarrVolume {
public:
    // Opens `path` (a folder or URL) at `level` as openZarrVolume does; throws IoError alike.
    ZarrVolume(const std::string& path, int level, const RemoteOptions& remote = {});
    ~ZarrVolume();

    // The root (a URL without its query), and " (level N)" after it for a level beyond 0.
    const std::string& name() const { return mName; }
    // The volume as it is converted: the store's sample type, spacing and origin from OME-Zarr.
    const VolumeInfo& info() const { return mInfo; }
    // Samples per chunk along x, y, z; chunks along x, y, z; every chunk of the grid.
    const Dims3& chunkShape() const { return mChunkShape; }
    const Dims3& chunkCounts() const { return mChunkCounts; }
    int64_t chunkCount() const { return mChunkCounts[0] * mChunkCounts[1] * mChunkCounts[2]; }
    // Chunk c's number, x fastest (the order of an index's pins).
    int64_t chunkNumber(const Dims3& c) const { return (c[2] * mChunkCounts[1] + c[1]) * mChunkCounts[0] + c[0]; }
    // Levels of the OME-Zarr image's multiscales (its datasets, finest first); 1 for a plain array.
    int levelCount() const;
    // CRC-32 of the array's metadata document (.zarray or zarr.json).
    uint32_t metadataCrc() const { return mMetadataCrc; }
    bool isRemote() const;
    // The array's folder or URL as messages show it ("ROOT/0").
    std::string arrayName() const;
    // The chunk's key as messages show it ("ROOT/0/c/0/1/2"; a shard's, with the inner chunk).
    std::string where(const Dims3& c) const;

    // The chunks' stored bytes (nullopt where missing), fetched in parallel when remote.
    // Throws IoError naming the chunk when it cannot be read or is larger than any encoding of
    // its samples.
    std::vector<std::optional<std::vector<unsigned char>>> stored(const std::vector<Dims3>& chunks) const;
    // Decodes chunk c's stored bytes (nullopt: the fill value) into out: the whole chunk,
    // chunkShape() samples x fastest of info().type (edge chunks padded as stored). Throws
    // IoError naming the chunk when they are corrupt or decode to another size.
    void decode(const Dims3& c, const std::optional<std::vector<unsigned char>>& bytes, unsigned char* out) const;
    // Bytes of one decoded chunk.
    size_t decodedBytes() const;

    // Remote requests sent and bytes received (0 for a folder).
    uint64_t requests() const;
    uint64_t bytesFetched() const;

private:
    struct Image;
    struct Place;
    Place place(const Dims3& c) const;
    // A shard's index, (offset, size) per inner chunk, read and checked once.
    std::shared_ptr<const std::vector<uint64_t>> shardIndex(const std::string& key, const ZarrKeys::Object& object) const;
    // A shard opened (null: missing); at a URL once, then kept (an open is a request).
    std::shared_ptr<const ZarrKeys::Object> shardObject(const std::string& key) const;

    std::unique_ptr<ZarrKeys> mKeys;
    std::unique_ptr<Image> mImage;
    std::string mName;
    VolumeInfo mInfo;
    Dims3 mChunkShape{}, mChunkCounts{};
    uint32_t mMetadataCrc = 0;
    mutable std::mutex mShardMutex;
    mutable std::map<std::string, std::shared_ptr<const std::vector<uint64_t>>> mShardIndexes;
    mutable std::map<std::string, std::shared_ptr<const ZarrKeys::Object>> mShardObjects;  // at a URL
};

// Throws IoError naming the store (and the chunk, for chunk errors) on any problem; for a level
// out of range, the message lists the levels and their shapes.
// `path` may be a URL (https://, http://, s3://: io/readers/zarr_keys.h), reached with `remote`.
// With `pins`, every chunk's pin is written to (*pins)[chunkNumber] as the chunk is read
// (resized to the chunk count; vdiso index).
std::unique_ptr<SliceReader> openZarrVolume(const std::string& path, int level,
                                            const RemoteOptions& remote = {},
                                            std::vector<ZarrChunkPin>* pins = nullptr);
// The same over an opened array. With `pinnedLayers` > 0 (a resumed index), `pins` already
// holds the pins of the chunks in layers below it, read by an earlier run: a chunk of those
// read again must match its pin, else IoError naming it.
std::unique_ptr<SliceReader> zarrSliceReader(std::unique_ptr<ZarrVolume> volume,
                                             std::vector<ZarrChunkPin>* pins = nullptr, int64_t pinnedLayers = 0);

// True if `dir` holds Zarr metadata (.zarray, .zgroup, .zattrs or zarr.json).
bool looksLikeZarr(const std::string& dir);

}  // namespace vdiso
