#include "serve/frame_stream.h"

#include <bit>
#include <mutex>

#include "serve/chunk_codec.h"
#include "serve/protocol.h"

namespace vdiso::serve {

namespace {

// REFs go out in batches this large (or before the next chunk, or at the frame's end); the
// first batch of a frame is small, so the nearest surface shows soon.
constexpr size_t kRefsPerBatch = 64, kRefsInFirstBatch = 4;

}  // namespace

size_t ClientChunks::KeyHash::operator()(const Key& k) const {
    uint64_t h = std::bit_cast<uint64_t>(k.iso) * 0x9E3779B97F4A7C15ull;
    h ^= (uint64_t(k.store) << 32 | k.brick) + 0x632BE59BD9B4E019ull + (h << 6) + (h >> 2);
    return size_t(h);
}

const uint32_t* ClientChunks::heldBy(const Key& key, uint32_t frame) const {
    const auto h = held.find(key);
    if (h != held.end()) return &h->second;
    if (frame != queuedFrame) return nullptr;
    const auto q = queued.find(key);
    return q == queued.end() ? nullptr : &q->second;
}

size_t ClientChunks::flushRefsLocked(Outbox& outbox, bool* refused) {
    if (pendingRefs.empty()) return 0;
    OutMessage m;
    m.bytes = std::make_shared<const std::vector<uint8_t>>(encodeRefs(pendingFrame, pendingRefs));
    m.frame = pendingFrame;
    pendingRefs.clear();
    const size_t bytes = m.bytes->size();
    // Never waits for room: an eviction's answer, queued under the same lock, must follow it.
    if (!outbox.push(std::move(m), false) && refused) *refused = true;
    return bytes;
}

FrameStream::FrameStream(ClientChunks& client, SharedChunks& shared, Outbox& outbox, uint32_t frame,
                         uint32_t store, double iso, const std::atomic<bool>& superseded,
                         std::chrono::steady_clock::time_point start, bool mayWait)
    : mClient(client), mShared(shared), mOutbox(outbox), mFrame(frame), mStore(store), mIso(iso),
      mSuperseded(superseded), mMayWait(mayWait), mStart(start), mTransient(frame, store, iso) {}

FrameStream::~FrameStream() {
    // Claims of bricks whose chunk this frame did not make (an error, or a stop, between the
    // brick's beginning and end): frames waiting for them go on without.
    for (const uint32_t b : mClaims) mShared.release(mIso, b);
}

void FrameStream::push(OutMessage m, bool waitForRoom) {
    if (!mOutbox.push(std::move(m), waitForRoom)) mRefused = true;
}

void FrameStream::flushRefsLocked() {
    bool refused = false;
    queued(mClient.flushRefsLocked(mOutbox, &refused));
    if (refused) mRefused = true;
}

void FrameStream::queued(size_t bytes) {
    mCounters.bytes += bytes;
    if (bytes && mCounters.firstChunkSeconds < 0)
        mCounters.firstChunkSeconds =
            std::chrono::duration<double>(std::chrono::steady_clock::now() - mStart).count();
}

bool FrameStream::beginBrick(int64_t brick, int level, double cellPixels, Use& use) {
    if (mSuperseded.load(std::memory_order_relaxed) || mRefused.load() || mOutbox.closed()) return false;
    const uint32_t b = uint32_t(brick);
    std::scoped_lock lock(mClient.mutex, mMutex);
    if (mWhole.contains(b) || mReferred.contains(b) || mFromShared.contains(b) || mSharedSent.contains(b) ||
        mClient.heldBy({mStore, mIso, b}, mFrame)) {
        use = Use::Held;
    } else if (sendsWhole(level, cellPixels)) {
        SharedChunks::Chunk chunk;
        switch (mShared.findOrClaim(mIso, b, chunk)) {
            case SharedChunks::Found::Held:  // made only to mark the pyramid; the shared chunk goes out
                use = Use::Held;
                mFromShared.emplace(b, std::move(chunk));
                break;
            case SharedChunks::Found::Encoding:  // another frame makes it: wait for it at the end
                use = Use::Held;
                mFromShared.emplace(b, std::nullopt);
                break;
            case SharedChunks::Found::Claimed:
                use = Use::Whole;
                mWhole.insert(b);
                mClaims.insert(b);
                break;
        }
    } else {
        use = Use::Part;
    }
    return true;
}

void FrameStream::endBrick(int64_t brick, Use use, const TriangleMesh& mesh, const PointSet& points,
                           const TriangleMesh& seams) {
    const uint32_t b = uint32_t(brick);
    // Caps between levels are this camera's: transient geometry, whatever the brick's use.
    if (!seams.indices.empty()) addTransient(seams, PointSet{});
    if (use == Use::Whole) {
        ChunkHeader header;
        header.flags = kChunkCacheable;
        header.frame = mFrame;
        header.store = mStore;
        header.brick = b;
        header.iso = mIso;
        auto message = std::make_shared<const std::vector<uint8_t>>(encodeChunk(header, mesh, PointSet{}));
        mShared.insert(mIso, b, {message, uint32_t(mesh.triangleCount())});
        {
            std::lock_guard lock(mMutex);
            mClaims.erase(b);
        }
        pushCacheable(b, std::move(message), uint32_t(mesh.triangleCount()));
        return;
    }
    if (use == Use::Held) {
        std::optional<SharedChunks::Chunk> shared;
        bool fromShared = false;
        {
            std::scoped_lock lock(mMutex);
            const auto found = mFromShared.find(b);
            if (found != mFromShared.end()) {  // the first strip to end it sends it
                shared = std::move(found->second);
                fromShared = true;
                mFromShared.erase(found);
                mSharedSent.insert(b);
            } else if (mSharedSent.contains(b)) {
                return;
            }
        }
        if (fromShared && !shared) shared = mShared.wait(mIso, b);  // another frame is encoding it
        if (shared) {
            pushCacheable(b, std::make_shared<const std::vector<uint8_t>>(SharedChunks::forFrame(*shared, mFrame)),
                          shared->triangles);
            return;
        }
        if (fromShared) {  // its encoder stopped: what was made of it here goes as transient geometry
            addTransient(mesh, points);
            return;
        }
        std::scoped_lock lock(mClient.mutex, mMutex);
        if (mWhole.contains(b) || mReferred.contains(b)) return;  // another strip has it
        if (const uint32_t* held = mClient.heldBy({mStore, mIso, b}, mFrame)) {
            mReferred.insert(b);
            ++mCounters.refs;
            mCounters.triangles += *held;
            mClient.pendingFrame = mFrame;
            mClient.pendingRefs.push_back(b);
            const size_t batch = mCounters.firstChunkSeconds < 0 ? kRefsInFirstBatch : kRefsPerBatch;
            if (mClient.pendingRefs.size() >= batch) flushRefsLocked();
            return;
        }
        // Evicted since beginBrick: what was made for it this frame goes as transient geometry.
    }
    addTransient(mesh, points);
}

void FrameStream::pushCacheable(uint32_t brick, std::shared_ptr<const std::vector<uint8_t>> message,
                                uint32_t triangles) {
    OutMessage m;
    m.bytes = std::move(message);
    m.frame = mFrame;
    m.cacheable = true;
    m.store = mStore;
    m.brick = brick;
    m.iso = mIso;
    m.triangles = triangles;
    const size_t bytes = m.bytes->size();
    const ClientChunks::Key key{mStore, mIso, brick};
    {
        std::scoped_lock lock(mClient.mutex, mMutex);
        mClient.pendingFrame = mFrame;
        flushRefsLocked();
        ++mCounters.chunks;
        mCounters.triangles += triangles;
        queued(bytes);
        // Held by the client from here for this frame's later passes (before the writer can
        // take it, which moves it to `held`).
        if (mClient.queuedFrame != mFrame) {
            mClient.queued.clear();
            mClient.queuedFrame = mFrame;
        }
        mClient.queued[key] = triangles;
    }
    if (!mOutbox.push(std::move(m), mMayWait)) {  // waits while the client is behind
        mRefused = true;
        std::lock_guard lock(mClient.mutex);
        mClient.queued.erase(key);
    }
}

bool TransientBatch::add(const TriangleMesh& mesh, const PointSet& points) {
    std::lock_guard lock(mMutex);
    const uint32_t offset = uint32_t(mMesh.positions.size());
    mMesh.positions.insert(mMesh.positions.end(), mesh.positions.begin(), mesh.positions.end());
    mMesh.normals.insert(mMesh.normals.end(), mesh.normals.begin(), mesh.normals.end());
    for (const uint32_t v : mesh.indices) mMesh.indices.push_back(v - mesh.firstVertex + offset);
    mPoints.positions.insert(mPoints.positions.end(), points.positions.begin(), points.positions.end());
    mPoints.normals.insert(mPoints.normals.end(), points.normals.begin(), points.normals.end());
    return mMesh.positions.size() + mPoints.size() >= fullAt();
}

std::optional<TransientBatch::Encoded> TransientBatch::take(bool force) {
    TriangleMesh mesh;
    PointSet points;
    {
        std::lock_guard lock(mMutex);
        const size_t held = mMesh.positions.size() + mPoints.size();
        if (held == 0 || (!force && held < fullAt())) return std::nullopt;
        mSentOne = true;
        std::swap(mesh, mMesh);
        std::swap(points, mPoints);
    }
    ChunkHeader header;
    header.frame = mFrame;
    header.store = mStore;
    header.iso = mIso;
    return Encoded{std::make_shared<const std::vector<uint8_t>>(encodeChunk(header, mesh, points)),
                   mesh.triangleCount(), points.size()};
}

void FrameStream::addTransient(const TriangleMesh& mesh, const PointSet& points) {
    if (!mTransient.add(mesh, points)) return;
    if (const auto chunk = mTransient.take(false)) pushTransient(*chunk);
}

void FrameStream::pushTransient(const TransientBatch::Encoded& chunk) {
    OutMessage m;
    m.bytes = chunk.bytes;
    m.frame = mFrame;
    {
        std::scoped_lock lock(mClient.mutex, mMutex);
        flushRefsLocked();
        ++mCounters.chunks;
        mCounters.triangles += chunk.triangles;
        mCounters.points += chunk.points;
        queued(m.bytes->size());
    }
    push(std::move(m), mMayWait);
}

void FrameStream::finish() {
    if (const auto chunk = mTransient.take(true)) pushTransient(*chunk);
    std::scoped_lock lock(mClient.mutex, mMutex);
    flushRefsLocked();
}

FrameCounters FrameStream::counters() {
    std::lock_guard lock(mMutex);
    return mCounters;
}

}  // namespace vdiso::serve
