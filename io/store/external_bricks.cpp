#include "io/store/external_bricks.h"

#include <algorithm>
#include <atomic>
#include <cstring>
#include <future>
#include <list>
#include <mutex>
#include <stdexcept>
#include <unordered_map>
#include <vector>

#include "core/brick_levels.h"
#include "io/crc32.h"
#include "io/error.h"

namespace vdiso {

namespace {

using ChunkSamples = std::shared_ptr<const std::vector<unsigned char>>;

std::string dimsText(const Dims3& d) {
    return std::to_string(d[0]) + " x " + std::to_string(d[1]) + " x " + std::to_string(d[2]);
}

// One level's array, its record and its bricks' place among the store's levels.
struct ArrayLevel {
    ZarrVolume array;
    ExternalLevel record;
    BrickLevel level;
    ArrayLevel(const std::string& location, int omeLevel, const RemoteOptions& remote)
        : array(location, omeLevel, remote) {}
};

}  // namespace

struct ExternalBricks::Impl {
    std::vector<std::unique_ptr<ArrayLevel>> levels;
    size_t cacheBytes;
    std::string again;  // what to do about a change

    // Decoded chunks by key (chunk number x kMaxLevels + level): being read (a future others
    // wait on) or held, least recently used last; `bytes` is 0 until the chunk is read.
    struct Slot {
        std::shared_future<ChunkSamples> samples;
        std::list<int64_t>::iterator used;
        size_t bytes = 0;
    };
    std::mutex mutex;
    std::unordered_map<int64_t, Slot> slots;
    std::list<int64_t> used;
    size_t heldBytes = 0;
    std::atomic<uint64_t> chunksRead{0}, chunkBytesRead{0};

    [[noreturn]] void changed(const ZarrVolume& array, const Dims3& c, const std::string& what) const {
        throwIoError(array.where(c), "changed since it was indexed (" + what + "): " + again);
    }

    // Chunk c's stored bytes checked against its pin, and decoded.
    ChunkSamples decodeChecked(const ArrayLevel& level, const Dims3& c, const std::optional<std::vector<unsigned char>>& stored) {
        const ZarrVolume& array = level.array;
        const ZarrChunkPin& pin = level.record.pins[size_t(array.chunkNumber(c))];
        if (!stored) {
            if (pin.bytes != ZarrChunkPin::kMissing)
                changed(array, c, "it is missing, where it held " + std::to_string(pin.bytes) + " bytes");
        } else if (pin.bytes == ZarrChunkPin::kMissing) {
            changed(array, c, "it was missing (the fill value) and now holds " + std::to_string(stored->size()) + " bytes");
        } else if (stored->size() != pin.bytes) {
            changed(array, c, "it holds " + std::to_string(stored->size()) + " bytes, where it held " +
                                  std::to_string(pin.bytes));
        } else if (crc32Of(stored->data(), stored->size()) != pin.crc) {
            changed(array, c, "its bytes differ from those indexed");
        }
        auto samples = std::make_shared<std::vector<unsigned char>>(array.decodedBytes());
        array.decode(c, stored, samples->data());
        chunksRead.fetch_add(1, std::memory_order_relaxed);
        chunkBytesRead.fetch_add(stored ? stored->size() : 0, std::memory_order_relaxed);
        return samples;
    }

    // Chunks cs of level `l`, decoded, each read once however many bricks ask for it at once:
    // those not held are fetched together (at a URL in parallel; a shard's neighbours in one
    // range: ZarrVolume::stored).
    std::vector<ChunkSamples> chunks(int l, const std::vector<Dims3>& cs) {
        const ArrayLevel& level = *levels[size_t(l)];
        auto keyOf = [&](const Dims3& c) { return level.array.chunkNumber(c) * kMaxLevels + l; };
        std::vector<std::shared_future<ChunkSamples>> futures(cs.size());
        std::vector<size_t> mine;
        std::vector<std::promise<ChunkSamples>> promises;
        promises.reserve(cs.size());
        std::unique_lock lock(mutex);
        for (size_t i = 0; i < cs.size(); ++i) {
            const int64_t key = keyOf(cs[i]);
            if (auto it = slots.find(key); it != slots.end()) {
                used.splice(used.begin(), used, it->second.used);
                futures[i] = it->second.samples;
                continue;
            }
            promises.emplace_back();
            used.push_front(key);
            futures[i] = slots.emplace(key, Slot{promises.back().get_future().share(), used.begin(), 0}).first->second.samples;
            mine.push_back(i);
        }
        lock.unlock();
        if (!mine.empty()) {
            size_t done = 0;
            try {
                std::vector<Dims3> wanted;
                for (const size_t i : mine) wanted.push_back(cs[i]);
                const auto stored = level.array.stored(wanted);
                for (; done < mine.size(); ++done) promises[done].set_value(decodeChecked(level, wanted[done], stored[done]));
            } catch (...) {
                lock.lock();
                for (size_t k = done; k < mine.size(); ++k) {
                    promises[k].set_exception(std::current_exception());
                    const int64_t key = keyOf(cs[mine[k]]);
                    used.erase(slots.at(key).used);
                    slots.erase(key);
                }
                throw;
            }
            lock.lock();
            for (const size_t i : mine) {
                Slot& slot = slots.at(keyOf(cs[i]));
                slot.bytes = futures[i].get()->size();
                heldBytes += slot.bytes;
            }
            // The least recently used read chunks go while over budget (the ones just read stay).
            for (auto it = std::prev(used.end()); heldBytes > cacheBytes && it != used.begin();) {
                auto slot = slots.find(*it);
                auto next = std::prev(it);
                const bool justRead = std::any_of(mine.begin(), mine.end(), [&](size_t i) { return keyOf(cs[i]) == *it; });
                if (slot->second.bytes && !justRead) {
                    heldBytes -= slot->second.bytes;
                    slots.erase(slot);
                    used.erase(it);
                }
                it = next;
            }
            lock.unlock();
        }
        std::vector<ChunkSamples> out;
        out.reserve(cs.size());
        for (auto& f : futures) out.push_back(f.get());
        return out;
    }
};

ExternalBricks::ExternalBricks(const std::string& indexPath, const StoreHeader& header, std::vector<ExternalLevel> records,
                               const RemoteOptions& remote, size_t cacheBytes)
    : mImpl(std::make_unique<Impl>()) {
    Impl& m = *mImpl;
    m.cacheBytes = cacheBytes;
    if (int(records.size()) != header.externalLevels)
        throwIoError(indexPath, "its record of the indexed data lists " + std::to_string(records.size()) +
                                    " levels where its header says " + std::to_string(header.externalLevels));
    const std::vector<BrickLevel> storeLevels = brickLevels(header.volume, header.brickSize, header.levelCount);
    // The arrays opened at once: at a URL each open is a few round trips.
    std::vector<std::future<std::unique_ptr<ArrayLevel>>> opening;
    for (const ExternalLevel& record : records)
        opening.push_back(std::async(std::launch::async, [&indexPath, &remote, &record] {
            return std::make_unique<ArrayLevel>(resolveExternalLocation(record.location, indexPath), record.level, remote);
        }));
    for (size_t l = 0; l < records.size(); ++l) {
        try {
            m.levels.push_back(opening[l].get());
        } catch (const IoError& e) {  // (the other opens are waited for as their futures go)
            throwIoError(indexPath, std::string("indexes data that cannot be opened: ") + e.what());
        }
        ArrayLevel& a = *m.levels.back();
        a.record = std::move(records[l]);
        a.level = storeLevels[l];
        if (l == 0)
            m.again = "run 'vdiso index' on " + a.array.name() + " again (" + indexPath + " is out of date)";
        const VolumeInfo& v = a.array.info();
        const Dims3& want = a.level.volume.dims;
        std::string problem;
        // Level 0 is the volume; a coarser level may be a few samples short of its dims.
        bool fits = true;
        for (int k = 0; k < 3; ++k) fits = fits && v.dims[k] <= want[k] && v.dims[k] >= want[k] - (l ? kScaleSamplesShort : 0);
        if (!fits)
            problem = "it is " + dimsText(v.dims) + " samples, the index's level " + std::to_string(l) + " " + dimsText(want);
        else if (v.type != header.volume.type)
            problem = std::string("its samples are ") + scalarTypeName(v.type) + ", the index's " +
                      scalarTypeName(header.volume.type);
        else if (a.array.chunkShape() != a.record.chunkShape || a.array.chunkCounts() != a.record.chunkCounts)
            problem = "its chunks are " + dimsText(a.array.chunkShape()) + " samples, the index's " +
                      dimsText(a.record.chunkShape);
        else if (l == 0 && (v.spacing != header.volume.spacing || v.origin != header.volume.origin))
            problem = "its spacing or origin differ from the index's";
        else if (a.array.metadataCrc() != a.record.metadataCrc)
            problem = "its metadata changed since it was indexed";
        if (!problem.empty())
            throwIoError(indexPath, "is not an index of " + a.array.name() + " as it is now (" + problem + "): " + m.again);
    }
}

ExternalBricks::~ExternalBricks() = default;

const std::string& ExternalBricks::name() const { return mImpl->levels[0]->array.name(); }
int ExternalBricks::levelCount() const { return int(mImpl->levels.size()); }
uint64_t ExternalBricks::chunksRead() const { return mImpl->chunksRead.load(); }
uint64_t ExternalBricks::chunkBytesRead() const { return mImpl->chunkBytesRead.load(); }
bool ExternalBricks::isRemote() const { return mImpl->levels[0]->array.isRemote(); }
uint64_t ExternalBricks::requests() const {
    uint64_t n = 0;
    for (const auto& a : mImpl->levels) n += a->array.requests();
    return n;
}
uint64_t ExternalBricks::bytesFetched() const {
    uint64_t n = 0;
    for (const auto& a : mImpl->levels) n += a->array.bytesFetched();
    return n;
}

void ExternalBricks::assemble(int64_t id, unsigned char* dst) const {
    Impl& m = *mImpl;
    int l = int(m.levels.size()) - 1;
    while (l > 0 && id < m.levels[size_t(l)]->level.firstBrick) --l;
    const ArrayLevel& level = *m.levels[size_t(l)];
    const BrickLayout& layout = level.level.layout;
    if (id - level.level.firstBrick >= layout.brickCount())
        throw std::logic_error("ExternalBricks::assemble: a brick of a level kept in the index file");
    const Dims3 coord = layout.brickCoord(id - level.level.firstBrick);
    const Dims3& chunk = level.array.chunkShape();
    const Dims3& dims = level.array.info().dims;  // its level's, or one or two samples fewer
    const int side = layout.side();
    const size_t sampleBytes = scalarSize(level.array.info().type);
    // A sample of the level, clamped to its faces and then to the array's own last sample.
    auto clamp = [&](int a, int64_t s) { return std::min(layout.clampSample(a, s), dims[a] - 1); };
    // The chunks holding the brick's samples, fetched first.
    Dims3 first{}, count{};
    for (int a = 0; a < 3; ++a) {
        const int64_t lo = clamp(a, layout.firstSample(coord[a]));
        const int64_t hi = clamp(a, layout.firstSample(coord[a]) + side - 1);
        first[a] = lo / chunk[a];
        count[a] = hi / chunk[a] - first[a] + 1;
    }
    std::vector<Dims3> wanted;
    wanted.reserve(size_t(count[0] * count[1] * count[2]));
    for (int64_t kz = 0; kz < count[2]; ++kz)
        for (int64_t ky = 0; ky < count[1]; ++ky)
            for (int64_t kx = 0; kx < count[0]; ++kx) wanted.push_back({first[0] + kx, first[1] + ky, first[2] + kz});
    const std::vector<ChunkSamples> chunks = m.chunks(l, wanted);
    // Rows as gatherBrick makes them (io/store/brick_encoder.cpp): the part inside the array
    // copied a chunk's run at a time, the ends clamped.
    const int64_t nx = dims[0];
    const int64_t x0 = layout.firstSample(coord[0]);
    const int begin = int(std::max<int64_t>(0, -x0));
    const int end = int(std::min<int64_t>(side, nx - x0));
    for (int lz = 0; lz < side; ++lz) {
        const int64_t z = clamp(2, layout.firstSample(coord[2]) + lz);
        const int64_t kz = z / chunk[2] - first[2], iz = z % chunk[2];
        for (int ly = 0; ly < side; ++ly) {
            const int64_t y = clamp(1, layout.firstSample(coord[1]) + ly);
            const int64_t ky = y / chunk[1] - first[1], iy = y % chunk[1];
            unsigned char* row = dst + (size_t(lz) * side + size_t(ly)) * side * sampleBytes;
            for (int lx = begin; lx < end;) {
                const int64_t x = x0 + lx;
                const int64_t kx = x / chunk[0] - first[0], ix = x % chunk[0];
                const int run = int(std::min<int64_t>(end - lx, chunk[0] - ix));
                const unsigned char* src = chunks[size_t((kz * count[1] + ky) * count[0] + kx)]->data() +
                                           size_t((iz * chunk[1] + iy) * chunk[0] + ix) * sampleBytes;
                std::memcpy(row + size_t(lx) * sampleBytes, src, size_t(run) * sampleBytes);
                lx += run;
            }
            for (int lx = 0; lx < begin; ++lx)
                std::memcpy(row + size_t(lx) * sampleBytes, row + size_t(begin) * sampleBytes, sampleBytes);
            for (int lx = end; lx < side; ++lx)
                std::memcpy(row + size_t(lx) * sampleBytes, row + size_t(end - 1) * sampleBytes, sampleBytes);
        }
    }
}

}  // namespace vdiso
