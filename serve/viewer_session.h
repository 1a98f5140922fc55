// One browser's session, apart from the socket: the protocol's messages in, frames out.
//
// The connection hands every message it reads to onMessage() and writes what nextToWrite()
// gives it, one at a time (its `wake` callback says when there is something). A VIEW replaces
// the pending camera and marks the running frame superseded, so the worker thread abandons it
// at its next brick and extracts for the newest camera: frames are never queued. Every
// malformed or invalid message is answered with an error message; the session goes on.
// close() stops the worker at its next brick and drops whatever is queued; the destructor
// joins it.
#pragma once

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <deque>
#include <cstdint>
#include <functional>
#include <mutex>
#include <optional>
#include <span>
#include <thread>

#include "serve/frame_stream.h"
#include "serve/outbox.h"
#include "serve/protocol.h"
#include "serve/store_catalog.h"

namespace vdiso::serve {

struct SessionSettings {
    int threads = 1;        // image strips per frame (core/extract/extract_view.h)
    int metaCellSize = 4;
    int prefetchBricks = 8;  // per frame
    int prefetchReaders = 2;  // threads loading them, per strip (more for stores at URLs)
    int prefetchNear = 2;     // of them read before they are known to show (BrickLookAhead)
    size_t outboxBytes = size_t(32) << 20;
    // Levels of detail (core/lod/view_levels.h): a VIEW's final frame is extracted at this error in
    // pixels (0: level 0 only); on a store with levels, a first frame at kCoarsePassFactor times
    // it comes before, so the viewer shows a coarse surface at once and refines it.
    double lodError = 1.0;
    static constexpr double kCoarsePassFactor = 8.0;
    // A viewer's frames start at most once in this time: VIEWs that come faster replace one
    // another while the next start waits, so a client sending VIEWs as fast as it can costs the
    // server 125 frame starts a second, not one per message. A browser sends one per animation
    // frame (16 ms at 60 Hz), which never waits.
    static constexpr std::chrono::milliseconds kMinFrameInterval{8};
};

// At most `slots` frames extract at once, so that their pinned bricks never fill a cache and
// the cores are not shared among more frames than keep them busy. Waiting frames go in turn, in
// the order they came, every coarse pass (a VIEW's first, quick picture: someone joining or
// turning the volume) before any final one, so that a viewer sees the volume at once however
// busy the server is.
class FrameGate {
public:
    explicit FrameGate(int slots) : mFree(slots) {}
    // Waits for a slot and its turn; false (no slot taken) once `giveUp` returns true.
    bool enter(const std::function<bool()>& giveUp, bool coarse = false);
    void leave();
    // Calls of enter so far: extraction passes begun (a VIEW's coarse and final frames).
    uint64_t entered() const { return mEntered.load(); }
    // Passes waiting now.
    size_t waiting() {
        std::lock_guard lock(mMutex);
        return mCoarse.size() + mFinal.size();
    }

private:
    std::mutex mMutex;
    std::condition_variable mChanged;
    int mFree;
    uint64_t mNextTicket = 0;
    std::deque<uint64_t> mCoarse, mFinal;  // tickets of the waiting passes, in order
    std::atomic<uint64_t> mEntered{0};
};

class ViewerSession {
public:
    ViewerSession(StoreCatalog& stores, const SessionSettings& settings, FrameGate& gate,
                  std::function<void()> wake);
    ~ViewerSession();
    ViewerSession(const ViewerSession&) = delete;
    ViewerSession& operator=(const ViewerSession&) = delete;

    // Starts the worker and queues the hello message; throws std::system_error, having queued
    // nothing, when no thread can be started for it.
    void start();
    void onMessage(std::span<const uint8_t> bytes, bool text);
    // A message above kMaxClientMessageBytes was skipped unread.
    void onOversize(uint64_t bytes);
    // The next message to write, if any; a cacheable chunk counts as held from here on.
    std::optional<OutMessage> nextToWrite();
    void close();
    // Waits for the worker to stop (after close()).
    void join();
    // The worker has finished (after close()): join() returns at once.
    bool stopped() const { return mWorkerDone.load() || !mWorker.joinable(); }
    bool backlogged() const { return mOutbox.backlogged(); }

private:
    void work();
    void runFrame(const ViewMessage& view, std::chrono::steady_clock::time_point arrival);
    // One frame of a VIEW at `lodError`; `final`: the last for it. Returns its status.
    std::string runPass(const ViewMessage& view, std::chrono::steady_clock::time_point arrival, double lodError,
                        bool final);
    void reply(const std::string& error, std::optional<uint32_t> seq = std::nullopt);

    StoreCatalog& mStores;
    const SessionSettings mSettings;
    FrameGate& mGate;
    Outbox mOutbox;
    ClientChunks mClient;

    std::mutex mMutex;
    std::condition_variable mWork;
    std::optional<ViewMessage> mPending;
    std::chrono::steady_clock::time_point mPendingArrival;
    std::chrono::steady_clock::time_point mLastStart;  // of the last frame (kMinFrameInterval)
    std::optional<uint32_t> mLastSeq;
    bool mClosing = false;
    std::atomic<bool> mSuperseded{false};
    std::mutex mJoinMutex;
    std::atomic<bool> mWorkerDone{false};
    std::thread mWorker;
};

}  // namespace vdiso::serve
