// Values worked out from a brick's samples, kept from one view-dependent extraction to the next
// (the frames of a moving camera, a viewer's clients): computed once while the brick stays in
// use, not once a frame. Meta-cell ranges (core/trees/meta_cell_range_cache.h) and the parts a
// coarse level lost (core/lod/thin_parts.h) are kept this way.
//
// Holds up to `maxBricks` bricks' values, dropping the least recently used. Each value is
// kept with the key it was made for (a meta-cell size, an isovalue): asked with another key,
// it is made again and replaces the kept one. Thread-safe: the image strips of one extraction
// share it; a value is made outside the lock (strips making the same one at once both do).
#pragma once

#include <cstddef>
#include <cstdint>
#include <list>
#include <memory>
#include <mutex>
#include <unordered_map>

namespace vdiso {

template <class Value>
class BrickMemo {
public:
    using Held = std::shared_ptr<const Value>;

    explicit BrickMemo(size_t maxBricks) : mMaxBricks(maxBricks) {}

    // Brick `id`'s value for `key`: the kept one, or make() (returning a Value), then kept.
    template <class Make>
    Held get(int64_t id, double key, Make&& make) {
        {
            std::lock_guard lock(mMutex);
            const auto it = mEntries.find(id);
            if (it != mEntries.end() && it->second.key == key) {
                mUse.splice(mUse.begin(), mUse, it->second.use);
                return it->second.value;
            }
        }
        Held value = std::make_shared<const Value>(make());
        std::lock_guard lock(mMutex);
        if (mMaxBricks == 0) return value;
        const auto it = mEntries.find(id);
        if (it != mEntries.end()) {
            it->second.value = value;
            it->second.key = key;
            mUse.splice(mUse.begin(), mUse, it->second.use);
            return value;
        }
        while (mEntries.size() >= mMaxBricks) {
            mEntries.erase(mUse.back());
            mUse.pop_back();
        }
        mUse.push_front(id);
        mEntries.emplace(id, Entry{value, key, mUse.begin()});
        return value;
    }

    size_t size() const {
        std::lock_guard lock(mMutex);
        return mEntries.size();
    }

private:
    struct Entry {
        Held value;
        double key;
        std::list<int64_t>::iterator use;
    };
    size_t mMaxBricks;
    std::unordered_map<int64_t, Entry> mEntries;
    std::list<int64_t> mUse;  // most recent first
    mutable std::mutex mMutex;
};

}  // namespace vdiso
