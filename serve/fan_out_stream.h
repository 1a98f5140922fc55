// One traversal, several clients' frames (follow mode): each brick's begin and end go to every
// client's FrameStream. The brick is made as the most demanding of them needs it (its whole
// surface if one client is to get it whole, else its visible part), and each stream sends what
// its own client lacks of it. Transient geometry that every client gets alike (a brick's
// visible part where none takes it whole, the caps between levels) is batched and encoded once
// here, its bytes queued to each. The first stream is the pass's own viewer: when it stops (a
// newer VIEW, a closed connection) the traversal stops; another stream that stops (a follower
// that does not keep up) only drops out of the rest of this frame. Thread-safe, as the strips
// need.
#pragma once

#include <cstdint>
#include <map>
#include <mutex>
#include <optional>
#include <thread>
#include <utility>
#include <vector>

#include "serve/frame_stream.h"

namespace vdiso::serve {

class FanOutStream final : public ViewStream {
public:
    // The streams' frame, store and isovalue, for the CHUNKs made once for all.
    FanOutStream(std::vector<FrameStream*> streams, uint32_t frame, uint32_t store, double iso);

    bool beginBrick(int64_t brick, int level, double cellPixels, Use& use) override;
    void endBrick(int64_t brick, Use use, const TriangleMesh& mesh, const PointSet& points,
                  const TriangleMesh& seams) override;
    // Queues what is still batched for all. Call once, after the extraction, before the
    // streams' own finish().
    void finish();

private:
    // Adds to the batch made once for all; queues it to each active stream when full (or, with
    // `force`, when it holds anything).
    void addShared(const TriangleMesh& mesh, const PointSet& points);
    void pushShared(bool force);

    std::vector<FrameStream*> mStreams;
    std::mutex mMutex;
    std::vector<bool> mActive;  // still in this frame
    // Each stream's use of a brick begun on a strip's thread (none: it was not in the frame
    // then); two strips may make the same brick.
    std::map<std::pair<int64_t, std::thread::id>, std::vector<std::optional<Use>>> mUses;
    TransientBatch mShared;
};

}  // namespace vdiso::serve
