#include "io/store/lazy_index.h"

#include <algorithm>
#include <optional>

#include <tbb/parallel_for.h>

#include "io/error.h"
#include "io/forked_child.h"

namespace vdiso {

LazyIndex::LazyIndex(const ByteSource& source, uint64_t offset, uint64_t storedBytes, uint64_t rawBytes,
                     std::span<const unsigned char> directoryCopy)
    : mSource(source), mOffset(offset) {
    const uint64_t directoryBytes = store_format::indexDirectoryBytes(rawBytes);
    if (storedBytes < directoryBytes) throwIoError(source.name(), "index is missing or corrupt (too short)");
    // The directory of `bytes`, or none when they do not decode as it (its checksum fails).
    auto tryDecode = [&](const unsigned char* bytes) -> std::optional<store_format::IndexDirectory> {
        try {
            return store_format::decodeIndexDirectory(bytes, storedBytes, rawBytes, source.name());
        } catch (const IoError&) {
            return std::nullopt;
        }
    };
    // The header's copy, when it is this directory: no read.
    std::optional<store_format::IndexDirectory> decoded;
    if (directoryCopy.size() == directoryBytes) decoded = tryDecode(directoryCopy.data());
    if (!decoded) {
        std::vector<unsigned char> directory(static_cast<size_t>(directoryBytes));
        // A remote disk cache keeps the directory once it decodes; what the check decoded last
        // is the directory as read.
        source.read(offset, directory.size(), directory.data(), "index directory", [&](size_t) {
            decoded = tryDecode(directory.data());
            return decoded.has_value();
        });
        // Decoded again where it failed, for the error naming what is wrong.
        if (!decoded) decoded = store_format::decodeIndexDirectory(directory.data(), storedBytes, rawBytes, source.name());
    }
    mDirectory = std::move(*decoded);
    // Untouched until a part lands: the pages of parts never asked for are never faulted in.
    mRaw = std::make_unique_for_overwrite<unsigned char[]>(size_t(rawBytes));
    mReady = std::make_unique<std::atomic<bool>[]>(size_t(mDirectory.parts()));
    for (uint64_t i = 0; i < mDirectory.parts(); ++i) mReady[i].store(false, std::memory_order_relaxed);
    mState.assign(size_t(mDirectory.parts()), State::Missing);
}

LazyIndex::~LazyIndex() {
    if (inForkedChild(mPid)) {  // (io/forked_child.h)
        for (std::thread& t : mBackground) abandonThread(t);
        return;
    }
    {
        std::lock_guard lock(mLock);
        mStop = true;
    }
    mChanged.notify_all();
    for (std::thread& t : mBackground) t.join();
}

void LazyIndex::load(uint64_t begin, uint64_t end) const {
    readParts(mDirectory.partOf(begin), mDirectory.partOf(end - 1) + 1, false);
}

void LazyIndex::readInBackground(uint64_t begin, size_t readers) {
    const uint64_t first = mDirectory.partOf(begin);
    readers = std::max<size_t>(readers, 1);
    mBackground.emplace_back([this, first, readers] {
        // `readers` parts in flight at once, each asked for alone (a part is here as soon as
        // its own answer is), the last part neither here nor on its way first; a source that
        // reads in the background holds no thread while they wait, and this one unpacks them.
        struct Part {
            uint64_t i;
            std::unique_ptr<unsigned char[]> stored;
            std::atomic<int8_t> good{-1};  // -1: not unpacked yet (a disk cache's check unpacks)
            std::exception_ptr failure;
        };
        std::mutex arrivedLock;
        std::condition_variable arrivedChanged;
        std::vector<Part*> arrived;
        size_t inFlight = 0;
        bool failed = false;
        for (;;) {
            std::vector<std::unique_ptr<Part>> starting;
            {
                // Chosen and claimed at once: a part is never asked for twice.
                std::lock_guard lock(mLock);
                uint64_t i = mDirectory.parts();
                while (!failed && !mStop && inFlight + starting.size() < readers) {
                    while (i > first && mState[i - 1] != State::Missing) --i;
                    if (i == first) break;
                    mState[--i] = State::OnItsWay;
                    starting.push_back(std::make_unique<Part>());
                    starting.back()->i = i;
                }
            }
            for (std::unique_ptr<Part>& owned : starting) {
                Part* part = owned.release();  // until it arrives
                const size_t n = size_t(mDirectory.offsets[part->i + 1] - mDirectory.offsets[part->i]);
                part->stored = std::make_unique_for_overwrite<unsigned char[]>(n);
                ++inFlight;
                // A remote disk cache keeps a part once it unpacks (its checksum passes).
                auto unpack = [this, part](size_t) {
                    part->good = store_format::unpackIndexPart(mDirectory, part->i, part->stored.get(),
                                                               mRaw.get() + part->i * store_format::kIndexPartBytes);
                    return part->good == 1;
                };
                mSource.readCoveringAsync(mOffset + mDirectory.offsets[part->i], n, part->stored.get(), {}, "index",
                                          unpack, &mStop, [&, part](std::exception_ptr e) {
                                              std::lock_guard lock(arrivedLock);
                                              part->failure = e;
                                              arrived.push_back(part);
                                              arrivedChanged.notify_one();
                                          });
            }
            if (inFlight == 0) return;
            std::vector<Part*> landed;
            {
                std::unique_lock lock(arrivedLock);
                arrivedChanged.wait(lock, [&] { return !arrived.empty(); });
                landed.swap(arrived);
            }
            for (Part* p : landed) {
                std::unique_ptr<Part> part(p);
                --inFlight;
                if (!part->failure && part->good < 0)
                    part->good = store_format::unpackIndexPart(mDirectory, part->i, part->stored.get(),
                                                               mRaw.get() + part->i * store_format::kIndexPartBytes);
                const bool good = !part->failure && part->good == 1;
                // A part that failed is left Missing, to be read when asked for (and its error met);
                // the background gives up.
                failed = failed || !good;
                {
                    std::lock_guard lock(mLock);
                    mState[part->i] = good ? State::Here : State::Missing;
                    if (good) mReady[part->i].store(true, std::memory_order_release);
                }
                mChanged.notify_all();
            }
        }
    });
}

bool LazyIndex::fetchParts(const std::vector<uint64_t>& mine, bool background) const {
    std::vector<std::unique_ptr<unsigned char[]>> stored(mine.size());
    std::vector<ByteRange> ranges(mine.size());
    for (size_t k = 0; k < mine.size(); ++k) {
        const uint64_t i = mine[k];
        const size_t n = size_t(mDirectory.offsets[i + 1] - mDirectory.offsets[i]);
        stored[k] = std::make_unique_for_overwrite<unsigned char[]>(n);
        ranges[k] = {mOffset + mDirectory.offsets[i], n, stored[k].get()};
    }
    std::exception_ptr failure;
    std::vector<char> good(mine.size(), 0), unpacked(mine.size(), 0);
    auto unpack = [&](size_t k) {
        const uint64_t i = mine[k];
        good[k] = store_format::unpackIndexPart(mDirectory, i, stored[k].get(),
                                               mRaw.get() + i * store_format::kIndexPartBytes);
        unpacked[k] = 1;
        return good[k] != 0;
    };
    try {
        // A remote disk cache keeps a part once it unpacks (its checksum passes).
        // In the background, a transfer in flight ends when the index is closed.
        mSource.readMany(ranges, "index", unpack, background ? &mStop : nullptr);
        tbb::parallel_for(size_t(0), mine.size(), [&](size_t k) {
            if (!unpacked[k]) unpack(k);
        });
    } catch (...) {
        failure = std::current_exception();
    }
    int64_t corrupt = -1;
    {
        std::lock_guard lock(mLock);
        for (size_t k = 0; k < mine.size(); ++k) {
            mState[mine[k]] = good[k] ? State::Here : State::Missing;
            if (good[k]) mReady[mine[k]].store(true, std::memory_order_release);
            else if (corrupt < 0 && !failure) corrupt = int64_t(mine[k]);
        }
    }
    mChanged.notify_all();
    if ((failure || corrupt >= 0) && background) return false;
    if (failure) std::rethrow_exception(failure);
    if (corrupt >= 0)
        throwIoError(mSource.name(), "index part " + std::to_string(corrupt) + " of " +
                                         std::to_string(mDirectory.parts()) +
                                         " is corrupt (checksum mismatch or bad zstd data)");
    return true;
}

bool LazyIndex::readParts(uint64_t first, uint64_t last, bool background) const {
    for (;;) {
        std::vector<uint64_t> mine;
        {
            std::lock_guard lock(mLock);
            for (uint64_t i = first; i < last; ++i)
                if (mState[i] == State::Missing) {
                    mState[i] = State::OnItsWay;
                    mine.push_back(i);
                }
        }
        if (!mine.empty() && !fetchParts(mine, background)) return false;
        std::unique_lock lock(mLock);
        auto settled = [&] {
            for (uint64_t i = first; i < last; ++i)
                if (mState[i] == State::OnItsWay) return false;
            return true;
        };
        mChanged.wait(lock, [&] { return settled() || (background && mStop.load()); });
        if (background && mStop) return false;
        bool all = true;
        for (uint64_t i = first; i < last; ++i) all = all && mState[i] == State::Here;
        if (all) return true;
        // Another reader's fetch of a part failed: read it here (and meet its error).
    }
}

}  // namespace vdiso
