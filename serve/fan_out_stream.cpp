#include "serve/fan_out_stream.h"

namespace vdiso::serve {

FanOutStream::FanOutStream(std::vector<FrameStream*> streams, uint32_t frame, uint32_t store, double iso)
    : mStreams(std::move(streams)), mActive(mStreams.size(), true), mShared(frame, store, iso) {}

bool FanOutStream::beginBrick(int64_t brick, int level, double cellPixels, Use& use) {
    std::vector<std::optional<Use>> uses(mStreams.size());
    bool any = false, whole = false, part = false;
    for (size_t i = 0; i < mStreams.size(); ++i) {
        {
            std::lock_guard lock(mMutex);
            if (!mActive[i]) continue;
        }
        Use own = Use::Part;
        if (!mStreams[i]->beginBrick(brick, level, cellPixels, own)) {
            if (i == 0) return false;  // the pass's own viewer: the traversal stops
            std::lock_guard lock(mMutex);
            mActive[i] = false;
            continue;
        }
        uses[i] = own;
        any = true;
        whole = whole || own == Use::Whole;
        part = part || own == Use::Part;
    }
    if (!any) return false;
    // Whole serves every use (a held brick's REF ignores the mesh); a part serves Held too.
    use = whole ? Use::Whole : part ? Use::Part : Use::Held;
    std::lock_guard lock(mMutex);
    mUses[{brick, std::this_thread::get_id()}] = std::move(uses);
    return true;
}

void FanOutStream::endBrick(int64_t brick, Use, const TriangleMesh& mesh, const PointSet& points,
                            const TriangleMesh& seams) {
    std::vector<std::optional<Use>> uses;
    std::vector<bool> active;
    {
        std::lock_guard lock(mMutex);
        const auto found = mUses.find({brick, std::this_thread::get_id()});
        if (found == mUses.end()) return;
        uses = std::move(found->second);
        mUses.erase(found);
        active = mActive;
    }
    // The caps are every client's transient geometry, and so is a part no client takes whole.
    if (!seams.indices.empty()) addShared(seams, PointSet{});
    bool allParts = true;
    for (size_t i = 0; i < mStreams.size(); ++i)
        if (uses[i] && active[i]) allParts = allParts && *uses[i] == Use::Part;
    if (allParts) {
        addShared(mesh, points);
        return;
    }
    const TriangleMesh none;
    for (size_t i = 0; i < mStreams.size(); ++i)
        if (uses[i] && active[i]) mStreams[i]->endBrick(brick, *uses[i], mesh, points, none);
}

void FanOutStream::addShared(const TriangleMesh& mesh, const PointSet& points) {
    if (mShared.add(mesh, points)) pushShared(false);
}

void FanOutStream::pushShared(bool force) {
    const auto chunk = mShared.take(force);
    if (!chunk) return;
    std::vector<bool> active;
    {
        std::lock_guard lock(mMutex);
        active = mActive;
    }
    for (size_t i = 0; i < mStreams.size(); ++i)
        if (active[i]) mStreams[i]->pushTransient(*chunk);
}

void FanOutStream::finish() { pushShared(true); }

}  // namespace vdiso::serve
