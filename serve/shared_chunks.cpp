#include "serve/shared_chunks.h"

#include <bit>
#include <chrono>
#include <span>

#include "serve/protocol.h"

namespace vdiso::serve {

size_t SharedChunks::KeyHash::operator()(const Key& k) const {
    return size_t(std::bit_cast<uint64_t>(k.iso) * 0x9E3779B97F4A7C15ull ^ (uint64_t(k.brick) + 0x632BE59BD9B4E019ull));
}

SharedChunks::Found SharedChunks::findOrClaim(double iso, uint32_t brick, Chunk& chunk) {
    std::lock_guard lock(mMutex);
    const auto at = mIndex.find({iso, brick});
    if (at != mIndex.end()) {
        mOrder.splice(mOrder.begin(), mOrder, at->second);
        ++mCounters.reused;
        chunk = at->second->second;
        return Found::Held;
    }
    if (mBudget == 0) return Found::Claimed;  // nothing is kept: every frame encodes its own
    return mClaimed.insert({iso, brick}).second ? Found::Claimed : Found::Encoding;
}

void SharedChunks::release(double iso, uint32_t brick) {
    {
        std::lock_guard lock(mMutex);
        mClaimed.erase({iso, brick});
    }
    mClaimEnded.notify_all();
}

std::optional<SharedChunks::Chunk> SharedChunks::wait(double iso, uint32_t brick) {
    std::unique_lock lock(mMutex);
    // Bounded: an encoder stuck on a read that never ends does not hold the waiter with it.
    if (!mClaimEnded.wait_for(lock, std::chrono::seconds(30), [&] { return !mClaimed.contains({iso, brick}); }))
        return std::nullopt;
    const auto at = mIndex.find({iso, brick});
    if (at == mIndex.end()) return std::nullopt;
    ++mCounters.reused;
    return at->second->second;
}

void SharedChunks::insert(double iso, uint32_t brick, Chunk chunk) {
    const uint64_t size = chunk.message->size();
    {
        std::lock_guard lock(mMutex);
        ++mCounters.encoded;
        mClaimed.erase({iso, brick});
        if (size <= mBudget && !mIndex.contains({iso, brick})) {
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
    }
    mClaimEnded.notify_all();
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
