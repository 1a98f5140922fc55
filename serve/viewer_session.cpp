#include "serve/viewer_session.h"

#include <algorithm>
#include <cstring>
#include <exception>

#include "core/clock.h"
#include "core/camera.h"
#include "io/json.h"

namespace vdiso::serve {


ViewerSession::ViewerSession(StoreCatalog& stores, const SessionSettings& settings, FramePool& pool,
                             std::function<void()> wake)
    : mStores(stores), mSettings(settings), mPool(pool), mOutbox(settings.outboxBytes, std::move(wake)) {}

ViewerSession::~ViewerSession() {
    close();
    join();
}

void ViewerSession::join() { mPool.join(*this); }

void ViewerSession::start() { mOutbox.push(OutMessage::control(mStores.hello())); }

void ViewerSession::close() {
    {
        std::lock_guard lock(mMutex);
        mClosing = true;
        mSuperseded = true;
        mPool.remove(*this);
    }
    mOutbox.close();
}

void ViewerSession::reply(const std::string& error, std::optional<uint32_t> seq) {
    JsonObject o;
    o.add("type", "error").add("message", error);
    if (seq) o.add("seq", int64_t(*seq));
    mOutbox.push(OutMessage::control(o.str()));
}

void ViewerSession::onOversize(uint64_t bytes) {
    reply("message of " + std::to_string(bytes) + " bytes is above the limit of " +
          std::to_string(kMaxClientMessageBytes) + "; ignored");
}

void ViewerSession::onMessage(std::span<const uint8_t> bytes, bool text) {
    try {
        if (text)
            throw ProtocolError("text message refused: a client sends binary VIEW and EVICT "
                                "messages (docs/protocol.md)");
        if (clientMessageType(bytes) == MessageType::View) {
            const ViewMessage view = parseView(bytes);
            if (view.store >= mStores.size())
                throw ProtocolError("VIEW: unknown store " + std::to_string(view.store) + " (" +
                                    std::to_string(mStores.size()) + " served)");
            const StoreHeader& h = mStores[view.store].reader->header();
            if (!(view.iso >= h.valueMin && view.iso <= h.valueMax))
                throw ProtocolError("VIEW: iso " + jsonNumber(view.iso) + " is outside store '" +
                                    mStores[view.store].name + "''s values [" + jsonNumber(h.valueMin) +
                                    ", " + jsonNumber(h.valueMax) + "]");
            {
                std::lock_guard lock(mMutex);
                if (mLastSeq && view.seq <= *mLastSeq)
                    throw ProtocolError("VIEW: seq " + std::to_string(view.seq) +
                                        " does not follow the last one (" + std::to_string(*mLastSeq) + ")");
                mLastSeq = view.seq;
                mPending = view;
                mFinalDue.reset();
                mPendingArrival = Clock::now();
                mSuperseded = true;  // the running frame stops at its next brick
                if (!mClosing) mPool.post(*this, true, mLastStart + SessionSettings::kMinFrameInterval);
            }
            mOutbox.beginFrame(view.seq);  // what is queued of older frames is dropped now
            return;
        }
        const EvictMessage evict = parseEvict(bytes);
        if (evict.store >= mStores.size())
            throw ProtocolError("EVICT: unknown store " + std::to_string(evict.store));
        std::lock_guard lock(mClient.mutex);
        // REFs decided before the eviction go out before its answer.
        mClient.flushRefsLocked(mOutbox);
        for (const uint32_t brick : evict.bricks) mClient.held.erase({evict.store, evict.iso, brick});
        mOutbox.push(OutMessage::control(
            JsonObject().add("type", "evicted").add("seq", int64_t(evict.seq)).str()));
    } catch (const ProtocolError& e) {
        // A refused VIEW is named by its seq when it has one, so the client can tell which.
        std::optional<uint32_t> seq;
        if (!text && bytes.size() >= 8 && bytes[0] == uint8_t(MessageType::View)) {
            uint32_t value;
            std::memcpy(&value, bytes.data() + 4, sizeof value);
            seq = value;
        }
        reply(e.what(), seq);
    }
}

std::optional<OutMessage> ViewerSession::nextToWrite() {
    std::optional<OutMessage> m = mOutbox.pop();
    if (m && m->cacheable) {
        std::lock_guard lock(mClient.mutex);
        mClient.held[{m->store, m->iso, m->brick}] = m->triangles;
    }
    return m;
}

void ViewerSession::runPass() {
    ViewMessage view;
    Clock::time_point arrival;
    bool first = false;
    {
        std::lock_guard lock(mMutex);
        if (mClosing) return;
        if (mPending) {
            first = true;
            mLastStart = Clock::now();
            view = *mPending;
            mPending.reset();
            mSuperseded = false;
        } else if (mFinalDue) {
            view = *mFinalDue;
            mFinalDue.reset();
        } else {
            return;
        }
        arrival = mPendingArrival;
    }
    const double lodError = mStores[view.store].reader->header().levelCount > 1 ? mSettings.lodError : 0.0;
    const bool coarse = first && lodError > 0;
    try {
        const std::string status =
            extractPass(view, arrival, coarse ? lodError * SessionSettings::kCoarsePassFactor : lodError, !coarse);
        // A complete coarse frame: the final one goes to the back of the queue, behind other
        // viewers' passes. Superseded (or failed): no finer one follows.
        if (coarse && status == "complete") {
            std::lock_guard lock(mMutex);
            if (!mPending && !mClosing) {
                mFinalDue = view;
                mPool.post(*this, false);
            }
        }
    } catch (const std::exception& e) {  // never past the pass: the server stays up
        reply("frame " + std::to_string(view.seq) + ": " + e.what(), view.seq);
    }
}

std::string ViewerSession::extractPass(const ViewMessage& view, Clock::time_point arrival, double lodError,
                                       bool final) {
    ServedStore& store = mStores[view.store];
    const VolumeInfo& volume = store.reader->volume();
    Camera camera = cameraOf(view);
    fitClipPlanes(camera, volume.origin, volume.worldMax());

    mOutbox.push(OutMessage::control(JsonObject()
                                         .add("type", "frameBegin")
                                         .add("frame", int64_t(view.seq))
                                         .add("store", int64_t(view.store))
                                         .addExact("iso", view.iso)
                                         .add("lodError", lodError)
                                         .add("final", final)
                                         .str()),
                 false);
    FrameStream stream(mClient, *store.chunks, mOutbox, view.seq, view.store, view.iso, mSuperseded, arrival);
    ViewExtractOptions options = ViewExtractOptions::sage(view.iso);
    options.metaCellSize = mSettings.metaCellSize;
    options.threads = mSettings.threads;
    options.prefetchBricks = mSettings.prefetchBricks;
    options.prefetchReaders = mSettings.prefetchReaders;
    options.prefetchNear = mSettings.prefetchNear;
    options.stream = &stream;
    options.rangeCache = store.ranges.get();
    options.tree = store.tree.get();
    options.lodError = lodError;
    const CacheCounters before = store.cache->counters();
    std::string status = "complete", error;
    ExtractStats stats;
    try {
        TriangleMesh unused;
        PointSet unusedPoints;
        stats = extractViewDependent(*store.cache, camera, options, unused, unusedPoints);
        if (stats.view.abandoned) status = "superseded";
    } catch (const std::exception& e) {  // a brick that cannot be read, say
        status = "error";
        error = e.what();
    }
    stream.finish();
    if (status == "complete" && stream.incomplete()) status = "superseded";
    if (!error.empty()) reply("frame " + std::to_string(view.seq) + ": " + error, view.seq);
    const FrameCounters c = stream.counters();
    const CacheCounters after = store.cache->counters();
    const double seconds = std::chrono::duration<double>(Clock::now() - arrival).count();
    auto frameEnd = [&](const std::string& said) {
        JsonObject end;
        end.add("type", "frameEnd").add("frame", int64_t(view.seq)).add("status", said);
        end.add("lodError", lodError).add("final", final);
        end.add("chunks", c.chunks).add("refs", c.refs).add("triangles", c.triangles);
        end.add("points", c.points).add("bytes", c.bytes);
        // The cache is shared: misses while this frame ran, whoever caused them.
        end.add("bricksRead", after.misses - before.misses);
        end.add("bricksVisited", stats.bricksActive);
        end.add("serverMs", seconds * 1e3);
        end.add("firstChunkMs", c.firstChunkSeconds < 0 ? -1.0 : c.firstChunkSeconds * 1e3);
        return end.str();
    };
    // If a newer frame drops any of this one's messages before they are written, the end
    // says so (serve/outbox.h).
    OutMessage end = OutMessage::control(frameEnd(status));
    end.ends = view.seq;
    if (status == "complete") end.ifIncomplete = OutMessage::control(frameEnd("superseded")).bytes;
    mOutbox.push(std::move(end));
    return status;
}

}  // namespace vdiso::serve
