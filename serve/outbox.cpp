#include "serve/outbox.h"

#include <algorithm>
#include <string>

namespace vdiso::serve {

OutMessage OutMessage::control(const std::string& json) {
    OutMessage m;
    m.bytes = std::make_shared<const std::vector<uint8_t>>(json.begin(), json.end());
    m.text = true;
    return m;
}

Outbox::Outbox(size_t byteLimit, std::function<void()> wake) : mLimit(byteLimit), mWake(std::move(wake)) {}

namespace {
size_t accounted(const OutMessage& m) { return m.bytes->size() + Outbox::kMessageOverhead; }
}  // namespace

bool Outbox::push(OutMessage m, bool waitForRoom) {
    {
        std::unique_lock lock(mMutex);
        auto superseded = [&] { return m.frame != OutMessage::kControl && mHasFrame && m.frame < mNewestFrame; };
        auto room = [&] { return mClosed || superseded() || mBytes <= mLimit; };
        // Control messages are small and never wait; frame messages wait for room while the
        // writer takes messages.
        if (m.frame != OutMessage::kControl && waitForRoom) {
            while (!room()) {
                const uint64_t pops = mPops;
                if (!mDrained.wait_for(lock, kPushPatience, [&] { return room() || mPops != pops; })) return false;
            }
        }
        if (mClosed || superseded()) return false;
        if (mQueue.empty()) mLastTaken = std::chrono::steady_clock::now();
        mBytes += accounted(m);
        if (m.frame == OutMessage::kControl) mControlBytes += accounted(m);
        mQueue.push_back(std::move(m));
    }
    mWake();
    return true;
}

void Outbox::beginFrame(uint32_t frame) {
    {
        std::lock_guard lock(mMutex);
        mHasFrame = true;
        mNewestFrame = std::max(mNewestFrame, frame);
        std::erase_if(mQueue, [&](const OutMessage& m) {
            const bool drop = m.frame != OutMessage::kControl && m.frame < mNewestFrame;
            if (drop) {
                mBytes -= accounted(m);
                if (std::find(mIncompleteFrames.begin(), mIncompleteFrames.end(), m.frame) == mIncompleteFrames.end())
                    mIncompleteFrames.push_back(m.frame);
                if (mIncompleteFrames.size() > 64) mIncompleteFrames.erase(mIncompleteFrames.begin());
            }
            return drop;
        });
    }
    mDrained.notify_all();
}

std::optional<OutMessage> Outbox::pop() {
    std::optional<OutMessage> m;
    {
        std::lock_guard lock(mMutex);
        if (mQueue.empty()) return std::nullopt;
        m = std::move(mQueue.front());
        mQueue.pop_front();
        mBytes -= accounted(*m);
        if (m->frame == OutMessage::kControl) mControlBytes -= accounted(*m);
        ++mPops;
        mLastTaken = std::chrono::steady_clock::now();
        if (m->ends != OutMessage::kControl) {
            const auto dropped = std::find(mIncompleteFrames.begin(), mIncompleteFrames.end(), m->ends);
            if (dropped != mIncompleteFrames.end()) {
                mIncompleteFrames.erase(dropped);
                if (m->ifIncomplete) m->bytes = m->ifIncomplete;
            }
        }
    }
    mDrained.notify_all();
    return m;
}

void Outbox::close() {
    {
        std::lock_guard lock(mMutex);
        mClosed = true;
        mQueue.clear();
        mBytes = 0;
        mControlBytes = 0;
    }
    mDrained.notify_all();
}

bool Outbox::closed() const {
    std::lock_guard lock(mMutex);
    return mClosed;
}

size_t Outbox::queuedBytes() const {
    std::lock_guard lock(mMutex);
    return mBytes;
}

bool Outbox::stalled() const {
    std::lock_guard lock(mMutex);
    return !mQueue.empty() && std::chrono::steady_clock::now() - mLastTaken > kPushPatience;
}

bool Outbox::backlogged() const {
    std::lock_guard lock(mMutex);
    return mBytes > mLimit || mControlBytes > kControlLimit;
}

}  // namespace vdiso::serve
