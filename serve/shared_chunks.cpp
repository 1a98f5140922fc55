#include "serve/shared_chunks.h"

#include <bit>
#include <span>

#include "serve/protocol.h"

namespace vdiso::serve {

size_t SharedChunks::KeyHash::operator()(const Key& k) const {
    return size_t(std::bit_cast<uint64_t>(k.iso) * 0x9E3779B97F4A7C15ull ^ (uint64_t(k.brick) + 0x632BE59BD9B4E019ull));
}

std::optional<SharedChunks::Chunk> SharedChunks::find(double iso, uint32_t brick) {
    std::lock_guard lock(mMutex);
    const auto at = mIndex.find({iso, brick});
    if (at == mIndex.end()) return std::nullopt;
    mOrder.splice(mOrder.begin(), mOrder, at->second);
    ++mCounters.reused;
    return at->second->second;
}

void SharedChunks::insert(double iso, uint32_t brick, Chunk chunk) {
    const uint64_t size = chunk.message->size();
    std::lock_guard lock(mMutex);
    ++mCounters.encoded;
    if (size > mBudget || mIndex.contains({iso, brick})) return;
    mOrder.emplace_front(Key{iso, brick}, std::move(chunk));
    mIndex.emplace(Key{iso, brick}, mOrder.begin());
    mCounters.bytes += size;
    while (mCounters.bytes > mBudget) {
        mCounters.bytes -= mOrder.back().second.message->size();
        mIndex.erase(mOrder.back().first);
        mOrder.pop_back();
        ++mCounters.evicted;
    }
}

std::vector<uint8_t> SharedChunks::forFrame(const Chunk& chunk, uint32_t frame) {
    std::vector<uint8_t> message(*chunk.message);
    ChunkHeader header = readChunkHeader(message);
    header.frame = frame;
    writeChunkHeader(header, message.data());
    return message;
}

SharedChunks::Counters SharedChunks::counters() const {
    std::lock_guard lock(mMutex);
    return mCounters;
}

}  // namespace vdiso::serve
