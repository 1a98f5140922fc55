// Encoded cacheable chunks of one store (CHUNK messages, serve/chunk_codec.h), shared by every
// viewer of the server. A brick's whole surface at an isovalue is the same for every camera and
// client (docs/protocol.md, "Chunks"), so the first frame that needs it extracts and encodes it,
// and every later one, of any viewer, sends these bytes with its own frame number: a viewer's
// own work is deciding what it sees. Least recently used first out, within a budget in bytes
// (what the entries' messages hold). A frame that finds a chunk being encoded by another
// (claimed, not yet put in) waits for it rather than encoding it again. Thread-safe.
#pragma once

#include <condition_variable>
#include <cstdint>
#include <list>
#include <memory>
#include <mutex>
#include <optional>
#include <unordered_map>
#include <unordered_set>
#include <vector>

namespace vdiso::serve {

class SharedChunks {
public:
    struct Chunk {
        std::shared_ptr<const std::vector<uint8_t>> message;  // its CHUNK, any frame number
        uint32_t triangles = 0;
    };
    struct Counters {
        uint64_t encoded = 0;  // chunks put in (each one encoding)
        uint64_t reused = 0;   // found
        uint64_t evicted = 0;
        uint64_t bytes = 0;    // held now
    };

    explicit SharedChunks(uint64_t budgetBytes) : mBudget(budgetBytes) {}

    enum class Found { Held, Claimed, Encoding };
    // The chunk of `brick` at `iso`: Held (in `chunk`; it becomes the most recently used);
    // Claimed: nobody has it, and the caller now encodes it (insert() or release() must
    // follow); Encoding: another caller has claimed it (wait() for it).
    Found findOrClaim(double iso, uint32_t brick, Chunk& chunk);
    // Holds a chunk just encoded, dropping the least recently used while over the budget (a
    // chunk larger than the whole budget is not held), and ends its claim.
    void insert(double iso, uint32_t brick, Chunk chunk);
    // Ends a claim without a chunk (the encoding frame stopped).
    void release(double iso, uint32_t brick);
    // Waits while the chunk is claimed; then the chunk if held (nullopt: its encoder stopped, or
    // it was too large to hold, or evicted already).
    std::optional<Chunk> wait(double iso, uint32_t brick);
    // Its CHUNK message with the frame number `frame`.
    static std::vector<uint8_t> forFrame(const Chunk& chunk, uint32_t frame);

    Counters counters() const;

private:
    struct Key {
        double iso;
        uint32_t brick;
        bool operator==(const Key&) const = default;
    };
    struct KeyHash {
        size_t operator()(const Key& k) const;
    };
    using Order = std::list<std::pair<Key, Chunk>>;  // most recently used first

    const uint64_t mBudget;
    mutable std::mutex mMutex;
    std::condition_variable mClaimEnded;
    std::unordered_set<Key, KeyHash> mClaimed;  // being encoded
    Order mOrder;
    std::unordered_map<Key, Order::iterator, KeyHash> mIndex;
    Counters mCounters;
};

}  // namespace vdiso::serve
