// The pieces of conversion into the brick store (docs/store-format.md) that every writer
// shares: the streaming writer (io/store/store_writer.h) and the one that shares the work among the
// ranks of an MPI job (mpi/convert_across_ranks.h) call the same functions, so they write the
// same bricks, entries, sub-block codes, histogram and header.
//
//   storeVolumeFor / storeLevelCount   validate the options against the volume, once
//   SliceWindow, MappedSlices          z-slices in memory: a ring or a slab of slices
//   readSlices, downsampleSlice        filling a window from a reader, or from the level below
//   BrickEncoder                       gather, measure (range, sub-blocks, histogram) and
//                                      compress bricks, in parallel (TBB), a group at a time
//   placeBricks, BrickGroupWriter      4 KiB-aligned offsets; one asynchronous write in flight
//   finishStore                        the histogram's coarsening, the index and the header
//
// None of these print; errors are thrown as the function says.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <future>
#include <memory>
#include <string>
#include <vector>

#include "core/brick_layout.h"
#include "core/brick_source.h"
#include "core/trees/sub_blocks.h"
#include "core/volume.h"
#include "io/store/brick_store.h"
#include "io/readers/slice_reader.h"
#include "io/store/store_writer.h"

namespace vdiso {

// Validates `options` against a volume that `sourceName` delivers (brick size, zstd level,
// dimensions, brick counts, orientation, --levels): throws std::invalid_argument for bad
// options, IoError naming the source for a volume the store cannot hold. Returns the volume as
// the store holds it (the direction's columns made unit length).
VolumeInfo storeVolumeFor(const VolumeInfo& source, const StoreWriteOptions& options,
                          const std::string& sourceName);

// Levels of detail the store will hold, level 0 included (options validated).
int storeLevelCount(const BrickLayout& level0, const StoreWriteOptions& options);

// The filter compressed bricks get: byte shuffle for multi-byte samples unless turned off.
BrickFilter storeFilterFor(ScalarType type, const StoreWriteOptions& options);

// The last slice layer `bk` of `layout` needs (its ghosts after included, clamped).
inline int64_t lastSliceOfLayer(const BrickLayout& layout, int64_t bk) {
    return std::min(layout.firstSample(bk) + layout.side() - 1, layout.dims[2] - 1);
}

// z-slices of one level held in memory: slice z in slot (z - first) mod slots, each slot
// sliceBytes. A ring (first 0, slots fewer than the slices) or a slab (first its first slice,
// slots its count). A view: it owns nothing.
struct SliceWindow {
    unsigned char* bytes = nullptr;
    size_t sliceBytes = 0;
    int64_t slots = 1;
    int64_t first = 0;
    unsigned char* slice(int64_t z) const { return bytes + size_t((z - first) % slots) * sliceBytes; }
};

// Address space for `slots` slices of dims[0] x dims[1] samples, mapped without reserving
// memory (MAP_NORESERVE), so its pages are only taken as slices arrive: a header that promises
// more data than its (compressed) file holds costs the memory of what it does hold. (An
// allocation from the heap would be the same on Linux, but a sanitizer's heap takes its size at
// its word.) Throws IoError naming `sourceName` and the memory it needs when the address space
// is not there (an address-space limit).
class MappedSlices {
public:
    MappedSlices(const Dims3& dims, size_t sampleBytes, int64_t slots, const std::string& sourceName);
    ~MappedSlices();
    MappedSlices(const MappedSlices&) = delete;
    MappedSlices& operator=(const MappedSlices&) = delete;
    int64_t slots() const { return mSlots; }
    SliceWindow window(int64_t first = 0) const { return {mBytes, mSliceBytes, mSlots, first}; }

private:
    unsigned char* mBytes = nullptr;
    size_t mMappedBytes = 0, mSliceBytes = 0;
    int64_t mSlots = 0;
};

// Reads slices [z0, z1) from `source`, which must be at slice z0, into their slots of `window`,
// in runs that do not wrap. Throws what the source throws.
void readSlices(SliceReader& source, const SliceWindow& window, int64_t z0, int64_t z1);

// Slice z of the level made from `fine` (core/lod/downsample.h): the tent filter of fine slices
// 2z-1, 2z, 2z+1 (clamped to fineDims[2]), which `fine` must hold, written to dst
// (coarseDims[0] x coarseDims[1] samples of `type`). Rows in parallel (TBB).
void downsampleSlice(ScalarType type, const SliceWindow& fine, const Dims3& fineDims,
                     const Dims3& coarseDims, int64_t z, unsigned char* dst);

// One brick as stored: its bytes (compressed or raw), its index entry (offset 0 until placed)
// and its sub-block codes.
struct EncodedBrick {
    std::vector<unsigned char> bytes;
    BrickEntry entry{};
    SubBlockCode subBlocks[kSubBlocksPerBrick];
};

// The histogram conversion counts before it knows the value range: 65536 bins keyed so that key
// order is value order for every type (exact for 8- and 16-bit integers; for floats the top 16
// bits of an order-preserving remapping of the IEEE bits, NaN in key 0). finishStore coarsens
// it to the index's kHistogramBins. Counts of several encoders (ranks) add up bin by bin.
constexpr int kFineHistogramBins = 1 << 16;

// Encodes bricks, keeping per-thread scratch (and the fine histogram) across calls. encode()
// runs its bricks in parallel on TBB's threads; one encode() at a time.
class BrickEncoder {
public:
    BrickEncoder(ScalarType type, const StoreWriteOptions& options);
    ~BrickEncoder();
    BrickEncoder(const BrickEncoder&) = delete;
    BrickEncoder& operator=(const BrickEncoder&) = delete;

    // Bricks [firstId, firstId + count) of `layout` (ids within that level), whose slices
    // `window` holds, into out[0, count) (grown as needed; later elements untouched). With
    // `countSamples` (level 0) the samples each brick owns count in the histogram; with
    // `external` (a level of an index that lies in the indexed data, io/store/zarr_index.h) the
    // bricks are measured and get no bytes. Throws on a compressor failure.
    void encode(const SliceWindow& window, const BrickLayout& layout, int64_t firstId, int64_t count,
                bool countSamples, bool external, std::vector<EncodedBrick>& out);

    // kFineHistogramBins counts: every sample counted so far, by all threads.
    std::vector<uint64_t> fineHistogram() const;

private:
    struct Impl;
    std::unique_ptr<Impl> mImpl;
};

// Brick rows of a layer encoded and written as one group: enough bricks (about 128) for every
// core, while the compressed bytes held stay a few MB whatever the layer's size.
inline int64_t brickRowsPerGroup(const BrickLayout& layout) {
    return std::max<int64_t>(1, 128 / layout.brickCounts[0]);
}

inline uint64_t alignToStore(uint64_t v) {
    return (v + kStoreAlignment - 1) / kStoreAlignment * kStoreAlignment;
}

// Gives bricks[0, count) consecutive offsets from `start` (a multiple of kStoreAlignment), each
// at a kStoreAlignment multiple, in order; returns the (aligned) end.
uint64_t placeBricks(std::vector<EncodedBrick>& bricks, int64_t count, uint64_t start);

// Bytes bricks[0, count) take when placed: placeBricks' end minus its start.
uint64_t placedBytes(const std::vector<EncodedBrick>& bricks, int64_t count);

// Writes groups of placed bricks into the file open as `fd` (named `path` in errors) on a
// thread of its own, one group in flight, while the caller encodes the next into the other of
// two buffers: neither core waits on the copy into the page cache. Writeback to disk is started
// for each group as it is written (sync_file_range), so the final flush has little left to do.
class BrickGroupWriter {
public:
    BrickGroupWriter(int fd, std::string path) : mFd(fd), mPath(std::move(path)) {}
    ~BrickGroupWriter();  // waits for the write in flight; its error is dropped (unwinding)
    BrickGroupWriter(const BrickGroupWriter&) = delete;
    BrickGroupWriter& operator=(const BrickGroupWriter&) = delete;

    // The buffer to encode the next group into: not the one being written.
    std::vector<EncodedBrick>& group() { return mGroups[mNext % 2]; }

    // Waits for the write in flight (throwing its IoError), then starts writing the first
    // `count` bricks of group() at their entries' offsets; they span [start, end).
    void write(int64_t count, uint64_t start, uint64_t end);

    // Waits for the write in flight; throws its IoError.
    void finish();

private:
    int mFd;
    std::string mPath;
    std::vector<EncodedBrick> mGroups[2];
    int64_t mNext = 0;
    std::future<void> mPending;
};

// The index and header of a store whose bricks are written: `entries` and `subBlocks`
// (kSubBlocksPerBrick per entry) for every brick of every level by id, level 0's first
// (`level0Bricks` of them), `fine` the fine histogram of level 0's samples, the index to go at
// `indexOffset`. The header's value range and the histogram are level 0's (coarse samples lie
// within it); the histogram spans the finite samples (-inf in the first bin, +inf in the last,
// NaN nowhere; where the range is infinite its finite end is the edge of the extreme finite fine
// bin).
struct StoreTail {
    StoreHeader header;
    std::array<unsigned char, kStoreHeaderBytes> headerBytes;  // to go at offset 0
    std::vector<unsigned char> index;                          // to go at header.indexOffset
    uint64_t level0Bytes = 0;                                  // stored bytes of level 0's bricks
};
// Throws IoError naming `inputName` when the volume has no finite sample (every one NaN or
// infinite): no isovalue lies in its range, and the store would claim a range it does not have.
StoreTail finishStore(const VolumeInfo& volume, const StoreWriteOptions& options, int levelCount,
                      int64_t level0Bricks, const std::vector<BrickEntry>& entries,
                      const std::vector<SubBlockCode>& subBlocks, const std::vector<uint64_t>& fine,
                      uint64_t indexOffset, const std::string& inputName);

}  // namespace vdiso
