// One browser's session, apart from the socket: the protocol's messages in, frames out.
//
// The connection hands every message it reads to onMessage() and writes what nextToWrite()
// gives it, one at a time (its `wake` callback says when there is something). A VIEW replaces
// the pending camera and marks the running frame superseded, so the pass running for it
// abandons it at its next brick, and posts the session to the server's frame pool
// (serve/frame_pool.h), whose workers run its passes in turn with every other viewer's: frames
// are never queued, and a session has no thread of its own. Every malformed or invalid message
// is answered with an error message; the session goes on. close() stops the running pass at
// its next brick and drops whatever is queued; the destructor waits for that pass. A client that
// does not read loses its passes until it does: a pass due while its outbox is backlogged runs
// once the outbox drains, so it takes no worker meanwhile. In follow
// mode (serve/session_directory.h) a leader's frames are written into its followers' outputs
// too, and a follower's VIEWs are refused.
#pragma once

#include <atomic>
#include <chrono>
#include <cstdint>
#include <functional>
#include <mutex>
#include <optional>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include "app/extract_settings.h"
#include "serve/frame_pool.h"
#include "serve/frame_stream.h"
#include "serve/outbox.h"
#include "serve/protocol.h"
#include "serve/session_directory.h"
#include "serve/store_catalog.h"

namespace vdiso::serve {

struct SessionSettings {
    // Every frame's extraction, as vdiso extract's (app/extract_settings.h): method sage, image
    // strips (threads), meta-cell size, read-ahead (prefetch bricks per frame, readers per
    // strip, near), and levels of detail: a VIEW's final frame is extracted at lodError pixels
    // (0: level 0 only); on a store with levels, a first frame at kCoarsePassFactor times it
    // comes before, so the viewer shows a coarse surface at once and refines it. Not when the
    // viewer's last final frame of that store and isovalue took at most kQuickFinalPass: the
    // viewer draws that frame until the new one ends, the new one streams front to back from its
    // start, and a coarse frame would only replace the fine surface with a coarse one for a
    // moment and delay the final one (a warm orbit step on a 512x512x234 CT: 82 ms with it, 38
    // without; bench/log.md). The isovalue is each VIEW's.
    ExtractSettings view;
    size_t outboxBytes = size_t(32) << 20;
    static constexpr double kCoarsePassFactor = 8.0;
    static constexpr std::chrono::milliseconds kQuickFinalPass{250};
    // A viewer's frames start at most once in this time: VIEWs that come faster replace one
    // another while the next start waits, so a client sending VIEWs as fast as it can costs the
    // server 125 frame starts a second, not one per message. A browser sends one per animation
    // frame (16 ms at 60 Hz), which never waits.
    static constexpr std::chrono::milliseconds kMinFrameInterval{8};
};

class ViewerSession final : private FramePool::Task, private FollowedSession {
public:
    ViewerSession(StoreCatalog& stores, const SessionSettings& settings, FramePool& pool,
                  SessionDirectory& directory, std::function<void()> wake);
    ~ViewerSession();
    ViewerSession(const ViewerSession&) = delete;
    ViewerSession& operator=(const ViewerSession&) = delete;

    // Enrolls the session in the directory and queues the hello message (with its session id);
    // with `follow` (a session id, from ?follow=ID), it follows that session, or is told why not
    // and leads its own frames.
    void start(const std::string& follow = "");
    void onMessage(std::span<const uint8_t> bytes, bool text);
    // A message above kMaxClientMessageBytes was skipped unread.
    void onOversize(uint64_t bytes);
    // The next message to write, if any; a cacheable chunk counts as held from here on.
    std::optional<OutMessage> nextToWrite();
    void close();
    // Waits for the running pass to stop (after close()).
    void join();
    // No pass runs (after close()): join() returns at once.
    bool stopped() { return mPool.idle(*this); }
    bool backlogged() const { return mOut->outbox.backlogged(); }
    const std::string& id() const { return mId; }

private:
    // FramePool::Task: the pending VIEW's first pass (its coarse frame on a store with levels of
    // detail, unless the last final pass of its surface was quick; else its only one: never
    // run nested in another viewer's pass, it goes to the queue instead), or the final pass due
    // after a complete coarse one, or a new follower's first frame. On a store with levels,
    // every final pass of a VIEW lets waiting first passes run inside it.
    void runPass() override;
    // FollowedSession
    void catchUp(std::shared_ptr<ViewerOutput> output, const ViewMessage& view) override;
    void stopLeading() override;
    // One frame of a VIEW at `lodError` into `outputs` (this viewer's, and its followers'; the
    // first one's stopping stops it); `final`: the last for it; `yields`: waiting first passes
    // run inside it (FramePool::runFirstPassesHere). Returns the first one's status, or "busy"
    // (nothing sent) for a nested pass whose output another pass holds.
    std::string extractPass(const ViewMessage& view, std::chrono::steady_clock::time_point arrival,
                            double lodError, bool final, const std::vector<std::shared_ptr<ViewerOutput>>& outputs,
                            bool yields);
    void reply(const std::string& error, std::optional<uint32_t> seq = std::nullopt);
    // The error of a VIEW's final pass on `store` in pixels: 0 (level 0 only) on a store without
    // levels of detail, which then has no coarse pass either.
    double finalLodError(uint32_t store) const;

    StoreCatalog& mStores;
    const SessionSettings mSettings;
    FramePool& mPool;
    SessionDirectory& mDirectory;
    const std::shared_ptr<ViewerOutput> mOut;
    std::string mId;

    std::mutex mMutex;
    std::optional<ViewMessage> mPending;  // its first pass not begun
    std::optional<ViewMessage> mFinalDue;  // its coarse pass complete, its final one not begun
    // The last final pass that ended complete, or ran past kQuickFinalPass before it was
    // superseded: whether the next VIEW of the same store and isovalue needs a coarse pass.
    struct FinalPass {
        uint32_t store = 0;
        double iso = 0;
        std::chrono::steady_clock::duration took{};
    };
    std::optional<FinalPass> mLastFinal;
    std::chrono::steady_clock::time_point mPendingArrival;
    std::chrono::steady_clock::time_point mLastStart;  // of the last frame (kMinFrameInterval)
    std::vector<std::pair<std::shared_ptr<ViewerOutput>, ViewMessage>> mCatchUps;  // new followers
    bool mClosing = false;
    // A pass came while the outbox was backlogged (the client not reading): it waits, queued
    // nowhere, until the writer takes a message and the outbox drains (nextToWrite).
    bool mWaitsForDrain = false;
    std::atomic<bool> mSuperseded{false};
};

}  // namespace vdiso::serve
