#include "serve/viewer_session.h"

#include <algorithm>
#include <array>
#include <cstring>
#include <exception>

#include "core/clock.h"
#include "core/camera.h"
#include "io/json.h"
#include "serve/fan_out_stream.h"

namespace vdiso::serve {

ViewerSession::ViewerSession(StoreCatalog& stores, const SessionSettings& settings, FramePool& pool,
                             SessionDirectory& directory, std::function<void()> wake)
    : mStores(stores), mSettings(settings), mPool(pool), mDirectory(directory),
      mOut(std::make_shared<ViewerOutput>(settings.outboxBytes, std::move(wake))) {}

ViewerSession::~ViewerSession() {
    close();
    join();
}

void ViewerSession::join() { mPool.join(*this); }

void ViewerSession::start(const std::string& follow) {
    mId = mDirectory.add(*this, mOut);
    mOut->outbox.push(OutMessage::control(mStores.hello(mId)));
    if (follow.empty()) return;
    try {
        mDirectory.follow(mId, follow);
    } catch (const ProtocolError& e) {  // this viewer leads its own frames instead
        reply(e.what());
    }
}

void ViewerSession::close() {
    // The directory first (its lock comes before this session's): no frame of a leader is
    // written here from now on, and if this session led, its first follower leads.
    if (!mId.empty()) mDirectory.remove(mId);
    {
        std::lock_guard lock(mMutex);
        mClosing = true;
        mSuperseded = true;
        mPool.remove(*this);
    }
    mOut->outbox.close();
}

void ViewerSession::catchUp(std::shared_ptr<ViewerOutput> output, const ViewMessage& view) {
    std::lock_guard lock(mMutex);
    if (mClosing) return;
    mCatchUps.emplace_back(std::move(output), view);
    mPool.post(*this, true);
}

void ViewerSession::stopLeading() {
    std::lock_guard lock(mMutex);
    mPending.reset();
    mFinalDue.reset();
    mCatchUps.clear();
    mSuperseded = true;
}

void ViewerSession::reply(const std::string& error, std::optional<uint32_t> seq) {
    JsonObject o;
    o.add("type", "error").add("message", error);
    if (seq) o.add("seq", int64_t(*seq));
    mOut->outbox.push(OutMessage::control(o.str()));
}

void ViewerSession::onOversize(uint64_t bytes) {
    reply("message of " + std::to_string(bytes) + " bytes is above the limit of " +
          std::to_string(kMaxClientMessageBytes) + "; ignored");
}

void ViewerSession::onMessage(std::span<const uint8_t> bytes, bool text) {
    try {
        if (text)
            throw ProtocolError("text message refused: a client sends binary VIEW, EVICT and HANDOVER "
                                "messages (docs/protocol.md)");
        const MessageType type = clientMessageType(bytes);
        if (type == MessageType::View) {
            const ViewMessage view = parseView(bytes);
            if (view.store >= mStores.size())
                throw ProtocolError("VIEW: unknown store " + std::to_string(view.store) + " (" +
                                    std::to_string(mStores.size()) + " served)");
            const StoreHeader& h = mStores[view.store].reader->header();
            if (!(view.iso >= h.valueMin && view.iso <= h.valueMax))
                throw ProtocolError("VIEW: iso " + jsonNumber(view.iso) + " is outside store '" +
                                    mStores[view.store].name + "''s values [" + jsonNumber(h.valueMin) +
                                    ", " + jsonNumber(h.valueMax) + "]");
            mDirectory.acceptView(mId, view);  // this viewer leads; the seq follows the group's last
            {
                std::lock_guard lock(mMutex);
                mPending = view;
                mFinalDue.reset();
                mCatchUps.clear();  // the new frame goes to every follower
                mPendingArrival = Clock::now();
                mSuperseded = true;  // the running frame stops at its next brick
                if (!mClosing) mPool.post(*this, true, mLastStart + SessionSettings::kMinFrameInterval);
            }
            // What is queued of older frames is dropped now, here and at the followers'.
            for (const std::shared_ptr<ViewerOutput>& out : mDirectory.outputsOf(mId)) out->outbox.beginFrame(view.seq);
            return;
        }
        if (type == MessageType::HandOver) {
            mDirectory.handOver(mId, parseHandOver(bytes).to);
            return;
        }
        const EvictMessage evict = parseEvict(bytes);
        if (evict.store >= mStores.size())
            throw ProtocolError("EVICT: unknown store " + std::to_string(evict.store));
        ClientChunks& client = mOut->client;
        std::lock_guard lock(client.mutex);
        // REFs decided before the eviction go out before its answer.
        client.flushRefsLocked(mOut->outbox);
        for (const uint32_t brick : evict.bricks) client.held.erase({evict.store, evict.iso, brick});
        mOut->outbox.push(OutMessage::control(
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
    std::optional<OutMessage> m = mOut->outbox.pop();
    if (m) {
        std::lock_guard lock(mMutex);
        if (mWaitsForDrain && !mClosing && !mOut->outbox.backlogged() && !mOut->outbox.stalled()) {
            mWaitsForDrain = false;
            mPool.post(*this, mPending.has_value() || !mCatchUps.empty());
        }
    }
    if (m && m->cacheable) {
        std::lock_guard lock(mOut->client.mutex);
        const ClientChunks::Key key{m->store, m->iso, m->brick};
        mOut->client.held[key] = m->triangles;
        mOut->client.queued.erase(key);
    }
    return m;
}

double ViewerSession::finalLodError(uint32_t store) const {
    return mStores[store].reader->header().levelCount > 1 ? mSettings.view.lodError : 0.0;
}

void ViewerSession::runPass() {
    ViewMessage view;
    Clock::time_point arrival;
    bool first = false;
    bool quickFinal = false;  // the last final pass of this store and isovalue was quick
    std::vector<std::shared_ptr<ViewerOutput>> catchUps;
    {
        std::lock_guard lock(mMutex);
        if (mClosing) return;
        if (mOut->outbox.backlogged() || mOut->outbox.stalled()) {  // not reading: no worker until it does
            mWaitsForDrain = true;
            return;
        }
        arrival = mPendingArrival;
        if (mPending) {
            // (A store without levels of detail has no coarse pass to skip.)
            quickFinal = finalLodError(mPending->store) > 0 && mLastFinal && mLastFinal->store == mPending->store && mLastFinal->iso == mPending->iso &&
                         mLastFinal->took <= SessionSettings::kQuickFinalPass;
            if (quickFinal && FramePool::nested()) {
                // Only coarse passes run inside another viewer's pass (on one thread, holding
                // it up): a final one goes to the queue, as after a coarse pass.
                mFinalDue = *mPending;
                mPending.reset();
                mSuperseded = false;
                mLastStart = Clock::now();
                mPool.post(*this, false);
                return;
            }
            first = true;
            mLastStart = Clock::now();
            view = *mPending;
            mPending.reset();
            mSuperseded = false;
        } else if (mFinalDue) {
            view = *mFinalDue;
            mFinalDue.reset();
        } else if (!mCatchUps.empty()) {
            view = mCatchUps.back().second;  // the group's view when the last one joined
            for (auto& [output, unused] : mCatchUps) catchUps.push_back(std::move(output));
            arrival = Clock::now();
        } else {
            return;
        }
        mCatchUps.clear();  // a VIEW's pass goes to every follower, new ones too
    }
    // A new follower's frame: the final one alone, into its output.
    const std::vector<std::shared_ptr<ViewerOutput>> outputs =
        catchUps.empty() ? mDirectory.outputsOf(mId) : catchUps;
    if (outputs.empty()) return;  // no longer leading
    const double lodError = finalLodError(view.store);
    const bool coarse = first && lodError > 0 && !quickFinal;
    try {
        // A final pass after a coarse one, or in its stead, lets first passes run inside it.
        const bool later = (!first || quickFinal) && catchUps.empty();
        const Clock::time_point begun = Clock::now();
        const std::string status = extractPass(
            view, arrival, coarse ? lodError * SessionSettings::kCoarsePassFactor : lodError, !coarse, outputs, later);
        const Clock::duration took = Clock::now() - begun;
        if (!coarse && catchUps.empty() &&
            (status == "complete" || (status == "superseded" && took > SessionSettings::kQuickFinalPass))) {
            std::lock_guard lock(mMutex);
            mLastFinal = FinalPass{view.store, view.iso, took};
        }
        if (status == "busy") {  // nested, an output taken by another pass: again, on its turn
            std::lock_guard lock(mMutex);
            if (!mClosing && !mPending) {
                if (!catchUps.empty()) {
                    for (auto& output : catchUps) mCatchUps.emplace_back(std::move(output), view);
                } else if (first) {
                    mPending = view;
                } else {
                    mFinalDue = view;
                }
                mPool.post(*this, first || !mCatchUps.empty());
            }
            return;
        }
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

namespace {

// A later pass's stream: between bricks, first passes waiting for a worker run here, nested
// (FramePool::runFirstPassesHere), so that a joining viewer does not wait for this whole pass.
class YieldToFirstPasses final : public ViewStream {
public:
    YieldToFirstPasses(ViewStream& inner, FramePool& pool, FramePool::Task& host)
        : mInner(inner), mPool(pool), mHost(host) {}
    bool beginBrick(int64_t brick, int level, double cellPixels, Use& use) override {
        if (mPool.firstPassWaits()) mPool.runFirstPassesHere(mHost);
        return mInner.beginBrick(brick, level, cellPixels, use);
    }
    void endBrick(int64_t brick, Use use, const TriangleMesh& mesh, const PointSet& points,
                  const TriangleMesh& seams) override {
        mInner.endBrick(brick, use, mesh, points, seams);
    }

private:
    ViewStream& mInner;
    FramePool& mPool;
    FramePool::Task& mHost;
};

std::string frameBegin(const ViewMessage& view, double lodError, bool final) {
    auto vec = [](const glm::dvec3& v) { return jsonArray(std::array<double, 3>{v.x, v.y, v.z}); };
    JsonObject camera;
    camera.addRaw("eye", vec(view.eye)).addRaw("target", vec(view.target)).addRaw("up", vec(view.up));
    camera.add("fov", view.fovYDegrees).add("width", int64_t(view.width)).add("height", int64_t(view.height));
    return JsonObject()
        .add("type", "frameBegin")
        .add("frame", int64_t(view.seq))
        .add("store", int64_t(view.store))
        .addExact("iso", view.iso)
        .add("lodError", lodError)
        .add("final", final)
        .addRaw("view", camera.str())
        .str();
}

}  // namespace

std::string ViewerSession::extractPass(const ViewMessage& view, Clock::time_point arrival, double lodError,
                                       bool final, const std::vector<std::shared_ptr<ViewerOutput>>& outputs,
                                       bool yields) {
    ServedStore& store = mStores[view.store];
    const VolumeInfo& volume = store.reader->volume();
    Camera camera = cameraOf(view);
    fitClipPlanes(camera, volume.origin, volume.worldMax());

    // Each output takes one frame at a time (a pass of the leader before a hand-over may still
    // be ending), in one order for every pass.
    std::vector<ViewerOutput*> order;
    for (const auto& out : outputs) order.push_back(out.get());
    std::sort(order.begin(), order.end());
    std::vector<std::unique_lock<std::mutex>> held;
    for (ViewerOutput* out : order) {
        // A pass nested in another (FramePool::runFirstPassesHere) never waits here while its
        // host holds outputs of its own: it gives way ("busy") and runs again later.
        if (FramePool::nested()) {
            std::unique_lock<std::mutex> lock(out->pass, std::try_to_lock);
            if (!lock.owns_lock()) return "busy";
            held.push_back(std::move(lock));
        } else {
            held.emplace_back(out->pass);
        }
    }

    const std::string begin = frameBegin(view, lodError, final);
    std::vector<std::unique_ptr<FrameStream>> streams;
    std::vector<FrameStream*> fanned;
    for (const auto& out : outputs) {
        out->outbox.beginFrame(view.seq);
        out->outbox.push(OutMessage::control(begin), false);
        // Only the pass's own viewer may make it wait for room (a follower drops out instead).
        streams.push_back(std::make_unique<FrameStream>(out->client, *store.chunks, out->outbox, view.seq, view.store,
                                                        view.iso, mSuperseded, arrival, streams.empty()));
        fanned.push_back(streams.back().get());
    }
    FanOutStream fanOut(fanned, view.seq, view.store, view.iso);
    // The session's settings for this VIEW's isovalue and pass, made into the core's options
    // as vdiso extract makes them (the cache's budget is checked once, by frameSlots).
    ExtractSettings frame = mSettings.view;
    frame.iso = view.iso;
    frame.lodError = lodError;
    ViewExtractOptions options = viewExtractOptions(frame, CachePlan{frame.prefetch, frame.threads});
    ViewStream& stream = streams.size() == 1 ? static_cast<ViewStream&>(*streams[0]) : fanOut;
    YieldToFirstPasses yielding(stream, mPool, *this);
    options.stream = yields ? &yielding : &stream;
    if (FramePool::nested()) {  // a first pass inside another's: one strip, no read-ahead threads
        options.threads = 1;
        options.prefetchBricks = 0;
    }
    options.rangeCache = store.ranges.get();
    options.lostParts = store.lostParts.get();
    options.tree = store.tree.get();
    const CacheCounters before = store.cache->counters();
    std::string status = "complete", error;
    ExtractStats stats;
    try {
        stats = streamViewDependent(*store.cache, camera, options);
        if (stats.view.abandoned) status = "superseded";
    } catch (const std::exception& e) {  // a brick that cannot be read, say
        status = "error";
        error = e.what();
    }
    if (streams.size() > 1) fanOut.finish();
    const CacheCounters after = store.cache->counters();
    const double seconds = std::chrono::duration<double>(Clock::now() - arrival).count();
    std::string firstStatus;
    for (size_t k = 0; k < outputs.size(); ++k) {
        FrameStream& member = *streams[k];
        Outbox& outbox = outputs[k]->outbox;
        member.finish();
        const std::string own = status == "complete" && member.incomplete() ? "superseded" : status;
        if (k == 0) firstStatus = own;
        if (!error.empty()) {
            JsonObject o;
            o.add("type", "error").add("message", "frame " + std::to_string(view.seq) + ": " + error);
            o.add("seq", int64_t(view.seq));
            outbox.push(OutMessage::control(o.str()));
        }
        const FrameCounters c = member.counters();
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
        OutMessage end = OutMessage::control(frameEnd(own));
        end.ends = view.seq;
        if (own == "complete") end.ifIncomplete = OutMessage::control(frameEnd("superseded")).bytes;
        outbox.push(std::move(end));
    }
    return firstStatus;
}

}  // namespace vdiso::serve
