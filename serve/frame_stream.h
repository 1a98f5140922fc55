// One frame of one client, streamed as the SAGE traversal makes it (core/extract/extract_view.h's
// ViewStream), and what that client holds across frames.
//
// Chunk policy (docs/protocol.md, "Chunks"): a visible brick the client holds already becomes
// a REF; a full-resolution one it lacks, whose cells are at least kWholeCellPixels on screen, a
// cacheable chunk of its whole surface (the same for every camera, so later frames only refer
// to it), taken from the store's shared chunks when another frame of any client encoded it
// (then only its visible part is made, to mark the pyramid), else extracted, encoded and shared;
// a smaller one, or one of a coarser level, goes to the frame's transient chunks the SAGE way
// (points, visible triangles).
// Refs and transient geometry are batched (a frame's first batch small); each cacheable chunk
// is encoded on the strip's thread and queued as soon as its brick is done, refs queued before
// it, so the stream stays front to back.
#pragma once

#include <atomic>
#include <chrono>
#include <cstdint>
#include <functional>
#include <memory>
#include <mutex>
#include <optional>
#include <unordered_map>
#include <unordered_set>
#include <vector>

#include "core/extract/extract_view.h"
#include "serve/outbox.h"
#include "serve/shared_chunks.h"

namespace vdiso::serve {

// Cells smaller than this on screen (pixels per cell side) are not worth sending whole: the
// brick's surface would cost more triangles than the pixels it covers.
constexpr double kWholeCellPixels = 0.5;
// Whether a brick goes whole. A coarse level's brick does not: a view takes it only where its
// cells span at most the level of detail's error (about a pixel), so its whole surface is
// several triangles a pixel, most of them hidden, and a step nearer or farther takes another
// level. On the 2560^3 head's normal view (all of it coarse bricks) whole chunks made the cold
// final frame 2.24 M triangles and 9.9 MB in 514 ms; parts 0.44 M, 3.4 MB, 263 ms (orbit steps
// then 3.6 MB, not 0.7 MB, and 206 ms, not 180 ms: bench/log.md).
inline bool sendsWhole(int level, double cellPixels) { return level == 0 && cellPixels >= kWholeCellPixels; }

// The cacheable chunks a client holds: sent (written to its socket) and not evicted. Guarded
// by `mutex`, which also orders a frame's REFS before an eviction's answer.
struct ClientChunks {
    struct Key {
        uint32_t store;
        double iso;
        uint32_t brick;
        bool operator==(const Key&) const = default;
    };
    struct KeyHash {
        size_t operator()(const Key& k) const;
    };
    std::mutex mutex;
    std::unordered_map<Key, uint32_t, KeyHash> held;  // -> triangles
    // Cacheable chunks queued in frame `queuedFrame` and not yet taken to be written. A later
    // pass of that same frame (a VIEW's final one after its coarse one) may name them in REFS:
    // the outbox writes in order and drops a frame's messages only for a newer frame, which
    // drops those REFS too.
    std::unordered_map<Key, uint32_t, KeyHash> queued;
    uint32_t queuedFrame = OutMessage::kControl;
    // The triangles of a chunk the client holds, or will before a REFS of `frame` reaches it.
    const uint32_t* heldBy(const Key& key, uint32_t frame) const;
    // REFs of the running frame not yet queued (flushed before an eviction is answered).
    uint32_t pendingFrame = 0;
    std::vector<uint32_t> pendingRefs;
    uint64_t pendingRefBytes = 0;

    // Queues the pending REFs as one REFS message (caller holds `mutex`); returns its bytes,
    // and sets *refused when the outbox refused it.
    size_t flushRefsLocked(Outbox& outbox, bool* refused = nullptr);
};

// Where one client's frames go: its outgoing queue and the chunks it holds. Shared by its
// session and, in follow mode (serve/session_directory.h), by the leader's frames, which
// write into every follower's. `pass` is held by the pass writing a frame into it, so that
// two frames never interleave there (a leader's pass and the one before a hand-over).
struct ViewerOutput {
    ViewerOutput(size_t outboxBytes, std::function<void()> wake) : outbox(outboxBytes, std::move(wake)) {}
    Outbox outbox;
    ClientChunks client;
    std::mutex pass;
};

// Transient geometry gathered into CHUNK messages of about kVertices vertices and points
// each (batches, so that a frame's small parts do not each cost a message), for one frame.
// Thread-safe: the strips add to it at once; a batch is encoded outside the lock.
class TransientBatch {
public:
    // A batch is sent at this many vertices (and points); a frame's first at kFirstVertices, so
    // that the nearest surface shows soon (as REFs: kRefsInFirstBatch).
    static constexpr size_t kVertices = 32768, kFirstVertices = 2048;
    // A transient CHUNK, encoded, and what it holds.
    struct Encoded {
        std::shared_ptr<const std::vector<uint8_t>> bytes;
        uint64_t triangles = 0, points = 0;
    };
    TransientBatch(uint32_t frame, uint32_t store, double iso) : mFrame(frame), mStore(store), mIso(iso) {}

    // Adds the geometry; returns whether the batch is full now.
    bool add(const TriangleMesh& mesh, const PointSet& points);
    // What is gathered, encoded as a CHUNK of the frame, when the batch is full, or with
    // `force` when it holds anything; the batch starts again empty.
    std::optional<Encoded> take(bool force);

private:
    const uint32_t mFrame, mStore;
    const double mIso;
    std::mutex mMutex;
    TriangleMesh mMesh;
    PointSet mPoints;
    bool mSentOne = false;  // a batch of this frame was taken
    // The vertices at which the batch is full (caller holds mMutex).
    size_t fullAt() const { return mSentOne ? kVertices : kFirstVertices; }
};

struct FrameCounters {
    uint64_t chunks = 0, refs = 0, triangles = 0, points = 0, bytes = 0;
    double firstChunkSeconds = -1;  // from the frame's start to its first CHUNK or REFS queued
};

class FrameStream final : public ViewStream {
public:
    // `superseded` is read before every brick: set, the frame is abandoned there.
    // `shared`: the store's chunks as encoded for every client. `mayWait`: a message waits
    // while the outbox is full (Outbox::push); else the frame stops for this client at once (a
    // follower, whose slowness must not hold up its leader's frame).
    FrameStream(ClientChunks& client, SharedChunks& shared, Outbox& outbox, uint32_t frame, uint32_t store,
                double iso, const std::atomic<bool>& superseded, std::chrono::steady_clock::time_point start,
                bool mayWait = true);
    ~FrameStream();
    FrameStream(const FrameStream&) = delete;
    FrameStream& operator=(const FrameStream&) = delete;

    bool beginBrick(int64_t brick, int level, double cellPixels, Use& use) override;
    void endBrick(int64_t brick, Use use, const TriangleMesh& mesh, const PointSet& points,
                  const TriangleMesh& seams) override;
    // Queues what is still batched. Call once, after the extraction.
    void finish();
    // Queues a transient CHUNK of this frame (its own batch's, or one encoded once for several
    // clients in follow mode: serve/fan_out_stream.h), counting it as this client's.
    void pushTransient(const TransientBatch::Encoded& chunk);
    FrameCounters counters();
    // A message of this frame could not be queued (superseded, closed, or the client stopped
    // reading): the frame is not whole, and the traversal stops at its next brick.
    bool incomplete() const { return mRefused.load(); }

private:
    // Adds to the frame's transient batch, sent when full (and at the end).
    void addTransient(const TriangleMesh& mesh, const PointSet& points);
    void queued(size_t bytes);  // counts bytes queued; notes the first
    void push(OutMessage m, bool waitForRoom);  // notes a refusal
    void flushRefsLocked();                      // the client's pending REFs; holds both locks

    // Queues a cacheable chunk's message (REFs decided before it first).
    void pushCacheable(uint32_t brick, std::shared_ptr<const std::vector<uint8_t>> message, uint32_t triangles);

    ClientChunks& mClient;
    SharedChunks& mShared;
    Outbox& mOutbox;
    const uint32_t mFrame, mStore;
    const double mIso;
    const std::atomic<bool>& mSuperseded;
    const bool mMayWait;
    std::atomic<bool> mRefused{false};
    const std::chrono::steady_clock::time_point mStart;
    std::mutex mMutex;  // below; taken after mClient.mutex when both are held
    std::unordered_set<uint32_t> mWhole, mReferred;  // bricks of this frame, by use
    // Bricks sent from the shared chunks: the chunk (until a strip sends it; none: another
    // frame is encoding it), and those sent; bricks this frame claimed to encode for all.
    std::unordered_map<uint32_t, std::optional<SharedChunks::Chunk>> mFromShared;
    std::unordered_set<uint32_t> mSharedSent, mClaims;
    TransientBatch mTransient;
    FrameCounters mCounters;
};

}  // namespace vdiso::serve
