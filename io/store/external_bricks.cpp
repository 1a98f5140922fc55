#include "io/store/external_bricks.h"

#include <algorithm>
#include <atomic>
#include <cstring>
#include <future>
#include <list>
#include <mutex>
#include <unordered_map>
#include <vector>

#include "io/crc32.h"
#include "io/error.h"

namespace vdiso {

namespace {

using ChunkSamples = std::shared_ptr<const std::vector<unsigned char>>;

std::string dimsText(const Dims3& d) {
    return std::to_string(d[0]) + " x " + std::to_string(d[1]) + " x " + std::to_string(d[2]);
}

}  // namespace

struct ExternalBricks::Impl {
    ZarrVolume array;
    ExternalLevel record;
    BrickLayout layout;
    size_t cacheBytes;
    std::string again;  // what to do about a change

    // Decoded chunks by number: being read (a future others wait on) or held, least recently
    // used last; `bytes` is 0 until the chunk is read.
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

    Impl(const std::string& location, int level, const RemoteOptions& remote)
        : array(location, level, remote) {}

    [[noreturn]] void changed(const Dims3& c, const std::string& what) const {
        throwIoError(array.where(c), "changed since it was indexed (" + what + "): " + again);
    }

    ChunkSamples load(const Dims3& c) {
        const auto stored = array.stored({c})[0];
        const ZarrChunkPin& pin = record.pins[size_t(array.chunkNumber(c))];
        if (!stored) {
            if (pin.bytes != ZarrChunkPin::kMissing)
                changed(c, "it is missing, where it held " + std::to_string(pin.bytes) + " bytes");
        } else if (pin.bytes == ZarrChunkPin::kMissing) {
            changed(c, "it was missing (the fill value) and now holds " + std::to_string(stored->size()) + " bytes");
        } else if (stored->size() != pin.bytes) {
            changed(c, "it holds " + std::to_string(stored->size()) + " bytes, where it held " +
                           std::to_string(pin.bytes));
        } else if (crc32Of(stored->data(), stored->size()) != pin.crc) {
            changed(c, "its bytes differ from those indexed");
        }
        auto samples = std::make_shared<std::vector<unsigned char>>(array.decodedBytes());
        array.decode(c, stored, samples->data());
        chunksRead.fetch_add(1, std::memory_order_relaxed);
        chunkBytesRead.fetch_add(stored ? stored->size() : 0, std::memory_order_relaxed);
        return samples;
    }

    // Chunk c's decoded samples, read once however many bricks ask for it at once.
    ChunkSamples chunk(const Dims3& c) {
        const int64_t number = array.chunkNumber(c);
        std::unique_lock lock(mutex);
        if (auto it = slots.find(number); it != slots.end()) {
            used.splice(used.begin(), used, it->second.used);
            const std::shared_future<ChunkSamples> samples = it->second.samples;
            lock.unlock();
            return samples.get();
        }
        std::promise<ChunkSamples> promise;
        used.push_front(number);
        slots.emplace(number, Slot{promise.get_future().share(), used.begin(), 0});
        lock.unlock();
        ChunkSamples samples;
        try {
            samples = load(c);
        } catch (...) {
            promise.set_exception(std::current_exception());
            lock.lock();
            used.erase(slots.at(number).used);
            slots.erase(number);
            throw;
        }
        promise.set_value(samples);
        lock.lock();
        slots.at(number).bytes = samples->size();
        heldBytes += samples->size();
        // The least recently used read chunks go while over budget (the one just read stays).
        for (auto it = std::prev(used.end()); heldBytes > cacheBytes && it != used.begin();) {
            auto slot = slots.find(*it);
            auto next = std::prev(it);
            if (slot->second.bytes) {
                heldBytes -= slot->second.bytes;
                slots.erase(slot);
                used.erase(it);
            }
            it = next;
        }
        return samples;
    }
};

ExternalBricks::ExternalBricks(const std::string& indexPath, const StoreHeader& header, ExternalLevel record,
                               const RemoteOptions& remote, size_t cacheBytes) {
    const std::string location = resolveExternalLocation(record.location, indexPath);
    try {
        mImpl = std::make_unique<Impl>(location, record.level, remote);
    } catch (const IoError& e) {
        throwIoError(indexPath, std::string("indexes data that cannot be opened: ") + e.what());
    }
    Impl& m = *mImpl;
    m.record = std::move(record);
    m.layout = BrickLayout(header.volume.dims, header.brickSize);
    m.cacheBytes = cacheBytes;
    m.again = "run 'vdiso index' on " + m.array.name() + " again (" + indexPath + " is out of date)";
    const VolumeInfo& v = m.array.info();
    std::string problem;
    if (v.dims != header.volume.dims)
        problem = "it is " + dimsText(v.dims) + " samples, the index " + dimsText(header.volume.dims);
    else if (v.type != header.volume.type)
        problem = std::string("its samples are ") + scalarTypeName(v.type) + ", the index's " +
                  scalarTypeName(header.volume.type);
    else if (m.array.chunkShape() != m.record.chunkShape || m.array.chunkCounts() != m.record.chunkCounts)
        problem = "its chunks are " + dimsText(m.array.chunkShape()) + " samples, the index's " +
                  dimsText(m.record.chunkShape);
    else if (v.spacing != header.volume.spacing || v.origin != header.volume.origin)
        problem = "its spacing or origin differ from the index's";
    else if (m.array.metadataCrc() != m.record.metadataCrc)
        problem = "its metadata changed since it was indexed";
    if (!problem.empty())
        throwIoError(indexPath, "is not an index of " + m.array.name() + " as it is now (" + problem + "): " + m.again);
}

ExternalBricks::~ExternalBricks() = default;

const std::string& ExternalBricks::name() const { return mImpl->array.name(); }
uint64_t ExternalBricks::chunksRead() const { return mImpl->chunksRead.load(); }
uint64_t ExternalBricks::chunkBytesRead() const { return mImpl->chunkBytesRead.load(); }
bool ExternalBricks::isRemote() const { return mImpl->array.isRemote(); }
uint64_t ExternalBricks::requests() const { return mImpl->array.requests(); }
uint64_t ExternalBricks::bytesFetched() const { return mImpl->array.bytesFetched(); }

void ExternalBricks::assemble(int64_t id, unsigned char* dst) const {
    Impl& m = *mImpl;
    const BrickLayout& layout = m.layout;
    const Dims3 coord = layout.brickCoord(id);
    const Dims3& chunk = m.array.chunkShape();
    const int side = layout.side();
    const size_t sampleBytes = scalarSize(m.array.info().type);
    // The chunks holding the brick's samples (clamped to the volume), fetched first.
    Dims3 first{}, count{};
    for (int a = 0; a < 3; ++a) {
        const int64_t lo = layout.clampSample(a, layout.firstSample(coord[a]));
        const int64_t hi = layout.clampSample(a, layout.firstSample(coord[a]) + side - 1);
        first[a] = lo / chunk[a];
        count[a] = hi / chunk[a] - first[a] + 1;
    }
    std::vector<ChunkSamples> chunks;
    chunks.reserve(size_t(count[0] * count[1] * count[2]));
    for (int64_t kz = 0; kz < count[2]; ++kz)
        for (int64_t ky = 0; ky < count[1]; ++ky)
            for (int64_t kx = 0; kx < count[0]; ++kx)
                chunks.push_back(m.chunk({first[0] + kx, first[1] + ky, first[2] + kz}));
    // Rows as gatherBrick makes them (io/store/brick_encoder.cpp): the part inside the volume
    // copied a chunk's run at a time, the ends clamped.
    const int64_t nx = layout.dims[0];
    const int64_t x0 = layout.firstSample(coord[0]);
    const int begin = int(std::max<int64_t>(0, -x0));
    const int end = int(std::min<int64_t>(side, nx - x0));
    for (int lz = 0; lz < side; ++lz) {
        const int64_t z = layout.clampSample(2, layout.firstSample(coord[2]) + lz);
        const int64_t kz = z / chunk[2] - first[2], iz = z % chunk[2];
        for (int ly = 0; ly < side; ++ly) {
            const int64_t y = layout.clampSample(1, layout.firstSample(coord[1]) + ly);
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
