// A session's outgoing messages: a queue bounded in bytes, where a newer frame replaces the
// unsent messages of older ones.
//
// The frame's producer (an extraction thread) pushes; the connection's writer pops one message
// at a time. Messages belong to a frame or are control messages (hello, errors, acks, frame
// ends), which are never dropped. beginFrame(f) drops every queued message of a frame before
// f: a slow client gets the newest frame, not a backlog of superseded ones. push() blocks while
// the queue holds more than its byte limit, until the writer drains it, the frame is
// superseded or the outbox is closed: so a slow client costs at most the limit (plus one
// message) of memory, never more. A message counts its bytes and kMessageOverhead (what
// holding it costs beside them), so a flood of small replies is bounded as truly as big chunks.
// Thread-safe.
#pragma once

#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <functional>
#include <memory>
#include <mutex>
#include <optional>
#include <vector>

namespace vdiso::serve {

struct OutMessage {
    static constexpr uint32_t kControl = UINT32_MAX;  // VIEW refuses this seq (serve/protocol.h)
    std::shared_ptr<const std::vector<uint8_t>> bytes;
    bool text = false;
    uint32_t frame = kControl;  // the frame it belongs to, or kControl
    // A frame's end (a control message): `bytes` says the frame is complete, `ifIncomplete`
    // what is written instead when a message of frame `ends` was dropped after all.
    uint32_t ends = kControl;
    std::shared_ptr<const std::vector<uint8_t>> ifIncomplete;
    // A cacheable chunk: once written, the client holds (store, iso, brick).
    bool cacheable = false;
    uint32_t store = 0, brick = 0, triangles = 0;
    double iso = 0;

    static OutMessage control(const std::string& json);
};

class Outbox {
public:
    // `wake` is called (outside the lock) when a message is queued, so the writer can start.
    Outbox(size_t byteLimit, std::function<void()> wake);

    // Queues `m`; a frame message first waits while the queue is over its limit, unless
    // `waitForRoom` is false (small messages queued under a lock the writer may need), for as
    // long as the writer takes messages, and at most kPushPatience after the last it took.
    // Returns false, queuing nothing, when the outbox is closed, m's frame is older than the
    // newest begun, or the wait ran out (a client that stopped reading: the frame is abandoned
    // rather than holding its pinned bricks and a worker).
    static constexpr std::chrono::milliseconds kPushPatience{500};
    static constexpr size_t kMessageOverhead = 192;
    // Control messages (errors, acks) queued beyond this make the outbox backlogged whatever
    // the limit: a client flooding bad messages without reading the replies is stopped early.
    static constexpr size_t kControlLimit = size_t(1) << 20;
    bool push(OutMessage m, bool waitForRoom = true);
    // Drops queued messages of frames before `frame`, and wakes a push blocked for them.
    void beginFrame(uint32_t frame);
    // The next message to write, or nothing.
    std::optional<OutMessage> pop();
    // Drops everything, refuses further pushes, releases blocked ones.
    void close();
    bool closed() const;
    size_t queuedBytes() const;
    // More is queued than the limit (or kControlLimit of control messages): the connection
    // stops reading the client's messages, and its viewer's frames wait, until it drains
    // (control messages, which never wait, stay bounded so).
    bool backlogged() const;
    // Messages have waited kPushPatience and the writer took none of them meanwhile: the client
    // is not reading (its socket is full). Its viewer's passes wait until it drains.
    bool stalled() const;

private:
    const size_t mLimit;
    std::function<void()> mWake;
    mutable std::mutex mMutex;
    std::condition_variable mDrained;
    std::deque<OutMessage> mQueue;
    size_t mBytes = 0, mControlBytes = 0;  // with kMessageOverhead each
    uint64_t mPops = 0;
    std::chrono::steady_clock::time_point mLastTaken;  // the last pop, or the first push into an empty queue
    bool mClosed = false;
    bool mHasFrame = false;
    uint32_t mNewestFrame = 0;
    std::vector<uint32_t> mIncompleteFrames;  // frames a message was dropped from
};

}  // namespace vdiso::serve
