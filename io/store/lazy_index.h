// A packed index (io/store/index_parts.h) read by parts as they are asked for: how a store of
// format 5 or later is opened. The store reader reads the parts of the bricks' entries at open
// and leaves the sub-block codes, three fifths of the stored index, for later: a local store
// reads and unpacks a part when it is first asked for; a remote one also fetches them in the
// background, last part first, one a request (the coarse levels' bricks are numbered last,
// and a distant view wants them first), and a part asked for before it came is fetched at once.
// So a view waits for the index bytes it looks at, not for the whole index. Internal to io/.
//
// Thread-safe: several threads may ask for bytes at once; a part is fetched by one of them and
// waited for by the others. A part that fails in the background is fetched again when asked
// for, and that fetch's error is thrown.
#pragma once

#include <atomic>
#include <condition_variable>
#include <cstdint>
#include <functional>
#include <memory>
#include <mutex>
#include <span>
#include <string>
#include <thread>
#include <vector>

#include <sys/types.h>
#include <unistd.h>

#include "io/store/byte_source.h"
#include "io/store/index_parts.h"

namespace vdiso {

class LazyIndex {
public:
    // Reads and validates the directory of the packed index of `storedBytes` at `offset` of
    // `source` (one read), which unpacks to rawBytes; or takes `directoryCopy` (the header's,
    // StoreHeader::indexDirectoryCopy) without a read when it decodes. No part is read yet.
    // Throws IoError.
    LazyIndex(const ByteSource& source, uint64_t offset, uint64_t storedBytes, uint64_t rawBytes,
              std::span<const unsigned char> directoryCopy = {});
    // Stops the background reading: the parts in flight are abandoned (their transfers end).
    ~LazyIndex();
    LazyIndex(const LazyIndex&) = delete;
    LazyIndex& operator=(const LazyIndex&) = delete;

    // The raw index. Bytes [begin, end) of it are valid once need(begin, end) has returned.
    const unsigned char* raw() const { return mRaw.get(); }
    uint64_t rawBytes() const { return mDirectory.rawBytes; }

    // Makes raw bytes [begin, end) valid: reads the parts holding them that are neither here
    // nor on their way (together: concurrently where the source can), waits for those on their
    // way. Cheap when they are here. Throws IoError naming the store and the part.
    void need(uint64_t begin, uint64_t end) const {
        for (uint64_t i = mDirectory.partOf(begin), last = mDirectory.partOf(end - 1); i <= last; ++i)
            if (!mReady[i].load(std::memory_order_acquire)) return load(begin, end);
    }

    // Starts reading every part holding raw bytes from `begin` on, the last part first, one a
    // request, `requests` at once, on one thread of its own that unpacks them (from a source
    // that reads in the background, no thread waits on a request).
    void readInBackground(uint64_t begin, size_t requests);

    // Parts asked for together (need(): the entries at the open) are read in requests of
    // consecutive parts, up to this many stored bytes each: a 2560^3 store's 19 parts of entries
    // went in as many requests.
    static constexpr uint64_t kRequestBytes = uint64_t(1) << 20;

private:
    enum class State : uint8_t { Missing, OnItsWay, Here };
    void load(uint64_t begin, uint64_t end) const;
    // Reads the parts [first, last) not here, as need() says, and waits for those on their way.
    void readParts(uint64_t first, uint64_t last) const;
    // Reads parts `mine` (ascending), claimed (OnItsWay) by the caller, in requests of
    // consecutive parts at once, and settles them; throws the first failure, or names a corrupt part.
    bool fetchParts(const std::vector<uint64_t>& mine) const;
    struct PartsRequest;
    // `parts` (ascending) cut into requests: consecutive, up to kRequestBytes stored each.
    std::vector<std::vector<uint64_t>> requestsFor(const std::vector<uint64_t>& parts) const;
    // Sends one request of consecutive parts; `arrived` once it has ended (on any thread).
    // `background`: a speculative read, whose failure does not end the object's other reads
    // (ByteSource::readCoveringAsync's `alone`): a part that fails is fetched again when asked for.
    void startRequest(PartsRequest& r, const std::atomic<bool>* cancel, std::function<void()> arrived,
                      bool background) const;
    // Unpacks what arrived and marks each part Here or Missing; whether all are here.
    bool settleRequest(PartsRequest& r) const;

    const ByteSource& mSource;
    uint64_t mOffset;
    store_format::IndexDirectory mDirectory;
    std::unique_ptr<unsigned char[]> mRaw;
    std::unique_ptr<std::atomic<bool>[]> mReady;  // per part: its raw bytes are valid
    mutable std::vector<State> mState;            // per part, under mLock
    mutable std::mutex mLock;
    mutable std::condition_variable mChanged;
    std::atomic<bool> mStop{false};
    std::vector<std::thread> mBackground;
    pid_t mPid = ::getpid();  // the process whose threads mBackground are
};

}  // namespace vdiso
