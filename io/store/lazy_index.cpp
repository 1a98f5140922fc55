#include "io/store/lazy_index.h"

#include <algorithm>
#include <condition_variable>
#include <functional>
#include <mutex>
#include <optional>
#include <stdexcept>

#include <tbb/parallel_for.h>

#include "core/thread_name.h"
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
        std::vector<unsigned char> directory(roomForRead(size_t(directoryBytes)));
        // A remote disk cache keeps the directory once it decodes; what the check decoded last
        // is the directory as read.
        source.read(offset, size_t(directoryBytes), directory.data(), "index directory", [&](size_t) {
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
    readParts(mDirectory.partOf(begin), mDirectory.partOf(end - 1) + 1);
}

// Consecutive parts read in one request: their stored bytes, one buffer, and what became of
// each (unpacked by the source's check when it has a disk cache, else after the answer).
struct LazyIndex::PartsRequest {
    std::vector<uint64_t> parts;
    std::unique_ptr<unsigned char[]> stored;
    std::unique_ptr<std::atomic<int8_t>[]> good;  // per part: -1 not unpacked yet, 0 corrupt, 1 here
    std::exception_ptr failure;
};

std::vector<std::vector<uint64_t>> LazyIndex::requestsFor(const std::vector<uint64_t>& parts) const {
    std::vector<std::vector<uint64_t>> requests;
    uint64_t bytes = 0;
    for (const uint64_t i : parts) {
        const uint64_t n = mDirectory.offsets[i + 1] - mDirectory.offsets[i];
        if (requests.empty() || requests.back().back() + 1 != i || bytes + n > kRequestBytes) {
            requests.emplace_back();
            bytes = 0;
        }
        requests.back().push_back(i);
        bytes += n;
    }
    return requests;
}

void LazyIndex::startRequest(PartsRequest& r, const std::atomic<bool>* cancel, std::function<void()> arrived,
                             bool background) const {
    const uint64_t first = mDirectory.offsets[r.parts.front()];
    const size_t n = size_t(mDirectory.offsets[r.parts.back() + 1] - first);
    r.stored = std::make_unique_for_overwrite<unsigned char[]>(roomForRead(n));
    r.good = std::make_unique<std::atomic<int8_t>[]>(r.parts.size());
    std::vector<ByteRange> pieces;
    for (size_t k = 0; k < r.parts.size(); ++k) {
        const uint64_t i = r.parts[k];
        r.good[k] = -1;
        pieces.push_back({mOffset + mDirectory.offsets[i], size_t(mDirectory.offsets[i + 1] - mDirectory.offsets[i]),
                          r.stored.get() + (mDirectory.offsets[i] - first)});
    }
    // A remote disk cache keeps a part once it unpacks (its checksum passes).
    auto unpack = [this, req = &r, at = pieces](size_t k) {
        req->good[k] = store_format::unpackIndexPart(mDirectory, req->parts[k], static_cast<unsigned char*>(at[k].dst),
                                                     mRaw.get() + req->parts[k] * store_format::kIndexPartBytes);
        return req->good[k] == 1;
    };
    mSource.readCoveringAsync(mOffset + first, n, r.stored.get(), std::move(pieces), "index", unpack, cancel,
                              [req = &r, arrived = std::move(arrived)](std::exception_ptr e) {
                                  req->failure = e;
                                  arrived();
                              },
                              background);
}

bool LazyIndex::settleRequest(PartsRequest& r) const {
    const uint64_t first = mDirectory.offsets[r.parts.front()];
    if (!r.good && !r.failure) r.failure = std::make_exception_ptr(std::logic_error("index request not sent"));
    bool all = !r.failure;
    for (size_t k = 0; k < r.parts.size(); ++k) {
        const uint64_t i = r.parts[k];
        if (!r.failure && r.good[k] < 0)
            r.good[k] = store_format::unpackIndexPart(mDirectory, i, r.stored.get() + (mDirectory.offsets[i] - first),
                                                      mRaw.get() + i * store_format::kIndexPartBytes);
        all = all && r.good[k] == 1;
    }
    {
        std::lock_guard lock(mLock);
        for (size_t k = 0; k < r.parts.size(); ++k) {
            const bool good = !r.failure && r.good[k] == 1;
            mState[r.parts[k]] = good ? State::Here : State::Missing;
            if (good) mReady[r.parts[k]].store(true, std::memory_order_release);
        }
    }
    mChanged.notify_all();
    return all;
}

void LazyIndex::readInBackground(uint64_t begin, size_t requests) {
    const uint64_t first = mDirectory.partOf(begin);
    requests = std::max<size_t>(requests, 1);
    mBackground.emplace_back([this, first, requests] {
        nameThisThread("vdiso-index");
        // `requests` in flight at once, each of the last part neither here nor on its way, alone
        // (a part is here as soon as its own answer is: grouped in requests of 1 MB, the parts a
        // normal view waited for came later, and its views took 1.1-1.2x as long; three a
        // request with as many parts in flight, 1.03-1.07x); a source that reads in the
        // background holds no thread while they wait, and this one unpacks them.
        std::mutex arrivedLock;
        std::condition_variable arrivedChanged;
        std::vector<PartsRequest*> arrived;
        size_t inFlight = 0;
        bool failed = false;
        for (;;) {
            std::vector<std::vector<uint64_t>> starting;
            {
                // Chosen and claimed at once: a part is never asked for twice.
                std::lock_guard lock(mLock);
                uint64_t i = mDirectory.parts();
                while (!failed && !mStop && inFlight + starting.size() < requests) {
                    while (i > first && mState[i - 1] != State::Missing) --i;
                    if (i == first) break;
                    mState[--i] = State::OnItsWay;
                    starting.push_back({i});
                }
            }
            for (std::vector<uint64_t>& request : starting) {
                auto* r = new PartsRequest{std::move(request), nullptr, nullptr, nullptr};
                ++inFlight;
                auto landed = [&, r] {
                    std::lock_guard lock(arrivedLock);
                    arrived.push_back(r);
                    arrivedChanged.notify_one();
                };
                try {
                    startRequest(*r, &mStop, landed, true);
                } catch (...) {  // not sent (it throws only before sending): settled as failed
                    r->failure = std::current_exception();
                    landed();
                }
            }
            if (inFlight == 0) return;
            std::vector<PartsRequest*> landed;
            {
                std::unique_lock lock(arrivedLock);
                arrivedChanged.wait(lock, [&] { return !arrived.empty(); });
                landed.swap(arrived);
            }
            for (PartsRequest* p : landed) {
                std::unique_ptr<PartsRequest> r(p);
                --inFlight;
                // A part that failed is left Missing, to be read when asked for (and its error
                // met); the background gives up.
                failed = !settleRequest(*r) || failed;
            }
        }
    });
}

bool LazyIndex::fetchParts(const std::vector<uint64_t>& mine) const {
    // Every request at once, then waited for.
    std::vector<std::unique_ptr<PartsRequest>> requests;
    std::mutex lock;
    std::condition_variable changed;
    size_t left = 0;
    try {
        for (std::vector<uint64_t>& parts : requestsFor(mine))
            requests.push_back(std::make_unique<PartsRequest>(PartsRequest{std::move(parts), nullptr, nullptr, nullptr}));
    } catch (...) {  // nothing sent: the parts go back to Missing
        {
            std::lock_guard hold(mLock);
            for (const uint64_t i : mine) mState[i] = State::Missing;
        }
        mChanged.notify_all();
        throw;
    }
    left = requests.size();
    auto landed = [&] {
        std::lock_guard hold(lock);
        if (--left == 0) changed.notify_one();
    };
    for (auto& r : requests) {
        try {
            startRequest(*r, nullptr, landed, false);
        } catch (...) {  // not sent (it throws only before sending): settled as failed
            r->failure = std::current_exception();
            landed();
        }
    }
    {
        std::unique_lock hold(lock);
        changed.wait(hold, [&] { return left == 0; });
    }
    std::vector<char> good(requests.size());
    tbb::parallel_for(size_t(0), requests.size(), [&](size_t k) { good[k] = settleRequest(*requests[k]); });
    for (size_t k = 0; k < requests.size(); ++k) {
        if (requests[k]->failure) std::rethrow_exception(requests[k]->failure);
        for (size_t j = 0; j < requests[k]->parts.size(); ++j)
            if (requests[k]->good[j] != 1)
                throwIoError(mSource.name(), "index part " + std::to_string(requests[k]->parts[j]) + " of " +
                                                 std::to_string(mDirectory.parts()) +
                                                 " is corrupt (checksum mismatch or bad zstd data)");
    }
    return true;
}

void LazyIndex::readParts(uint64_t first, uint64_t last) const {
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
        if (!mine.empty()) fetchParts(mine);
        std::unique_lock lock(mLock);
        auto settled = [&] {
            for (uint64_t i = first; i < last; ++i)
                if (mState[i] == State::OnItsWay) return false;
            return true;
        };
        // In a process forked from the one that opened the index, parts on their way were the
        // parent's requests: none will come here.
        if (inForkedChild(mPid) && !settled())
            throwIoError(mSource.name(), "its index was being read when the process forked: a store opened before "
                                         "fork() cannot be read in the child process: open it again there");
        mChanged.wait(lock, settled);
        bool all = true;
        for (uint64_t i = first; i < last; ++i) all = all && mState[i] == State::Here;
        if (all) return;
        // Another reader's fetch of a part failed: read it here (and meet its error).
    }
}

}  // namespace vdiso
