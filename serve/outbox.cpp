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

bool Outbox::push(OutMessage m, bool waitForRoom) {
    {
        std::unique_lock lock(mMutex);
        auto superseded = [&] { return m.frame != OutMessage::kControl && mHasFrame && m.frame < mNewestFrame; };
        // Control messages are small and never wait; frame messages wait for room.
        if (m.frame != OutMessage::kControl && waitForRoom &&
            !mDrained.wait_for(lock, kPushPatience, [&] { return mClosed || superseded() || mBytes <= mLimit; }))
            return false;
        if (mClosed || superseded()) return false;
        mBytes += m.bytes->size();
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
                mBytes -= m.bytes->size();
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
        mBytes -= m->bytes->size();
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

}  // namespace vdiso::serve
