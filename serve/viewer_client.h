// A client of `vdiso serve` in C++: what the browser does, without drawing. It connects with
// the token, sends VIEWs and EVICTs, decodes the chunks, keeps the cacheable ones by what they
// hold (store, iso, brick) and assembles each frame from the chunks it names. The tests check
// frames against the library with it, and bench/ measures latency and bytes with it.
// Blocking calls on one thread; not thread-safe (one client per thread).
#pragma once

#include <chrono>
#include <cstdint>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <tuple>
#include <vector>

#include "serve/chunk_codec.h"
#include "serve/protocol.h"

namespace vdiso::serve {

struct ClientFrame {
    uint32_t frame = 0;
    uint32_t store = 0;  // the VIEW's
    double iso = 0;
    std::string status;    // frameEnd's status: "complete", "superseded", "error"
    std::string frameEnd;  // the frameEnd message as it came
    std::vector<uint32_t> chunks;  // cacheable chunks received, in arrival order
    std::vector<uint32_t> refs;    // chunks named by REFS, in arrival order
    std::vector<DecodedChunk> transient;
    uint64_t binaryBytes = 0;      // CHUNK and REFS bytes received for this frame
    uint64_t missingRefs = 0;      // REFS naming a chunk the client does not hold
    double firstGeometrySeconds = -1;  // from sending the VIEW to the first CHUNK or REFS
    double completeSeconds = -1;       // to frameEnd
    std::vector<std::string> errors;   // error messages that arrived meanwhile
    int framesBegun = 0;               // frameBegin messages (of any frame) that arrived meanwhile
    // Coarser frames of the same VIEW that came first (levels of detail: frameEnd's "final"
    // false); the fields above are the final frame's. -1: none.
    int coarseFrames = 0;
    double coarseCompleteSeconds = -1;  // to the first coarse frame's end
    uint64_t coarseTriangles = 0;       // that frame's, as its frameEnd says
};

class ViewerClient {
public:
    // Connects to ws://host:port/ws?token=TOKEN (&QUERY, e.g. follow=ID) and reads the hello.
    // Throws IoError (refused, handshake failed) or ProtocolError (no hello).
    ViewerClient(const std::string& host, uint16_t port, const std::string& token, const std::string& query = "");
    ~ViewerClient();
    ViewerClient(const ViewerClient&) = delete;
    ViewerClient& operator=(const ViewerClient&) = delete;

    const std::string& hello() const { return mHello; }
    // This viewer's session id, from the hello (what ?follow= names).
    std::string session() const;

    // Sends raw bytes as one message (binary, or text), for tests of what the server refuses.
    void sendRaw(const std::vector<uint8_t>& bytes, bool text = false);
    // Sends a VIEW and returns when its frameEnd has arrived (frames of older VIEWs that
    // arrive meanwhile are read and discarded).
    ClientFrame requestFrame(const ViewMessage& view);
    // Sends a VIEW without waiting.
    void sendView(const ViewMessage& view);
    // Reads until the frameEnd of `frame`.
    ClientFrame readFrame(uint32_t frame);
    // A follower's next frame (follow mode): from the next frameBegin, whatever its number, to
    // its final frameEnd (a newer frame beginning first takes its place).
    ClientFrame readFollowedFrame();
    // The next text message (skipping binary ones). Throws IoError when the connection ends.
    std::string readText();
    // Drops chunks from the cache, tells the server, and waits for its answer.
    void evict(uint32_t store, double iso, const std::vector<uint32_t>& bricks);

    // The frame's geometry: the cacheable chunks it names, from the cache, and its transient
    // chunks, in one mesh (firstVertex 0) and one point set.
    void assemble(const ClientFrame& frame, TriangleMesh& mesh, PointSet& points) const;
    size_t cachedChunks() const { return mCache.size(); }
    // The bytes of the CHUNK message that brought a cached chunk (0 if not cached).
    uint64_t chunkBytes(uint32_t store, double iso, uint32_t brick) const;
    bool holds(uint32_t store, double iso, uint32_t brick) const {
        return mCache.contains({store, iso, brick});
    }
    void close();
    // false: chunks are kept by their headers alone, undecoded (a load generator that measures
    // the server, not its clients: frames then assemble to no geometry).
    void setDecode(bool decode) { mDecode = decode; }
    // From another thread: shuts the socket down, so that a read blocked on it ends (with an
    // IoError) and no more is sent. The only call that may come from another thread.
    void interrupt();

private:
    struct Connection;
    // One message; true when it is text.
    bool read(std::vector<uint8_t>& message);
    // Reads f's frame to its final frameEnd; `followed`: f is not known yet (its frameBegin says).
    ClientFrame readUntilEnd(ClientFrame f, bool followed);
    // The chunk decoded, or its header alone (setDecode(false)).
    DecodedChunk decodeOrNot(const std::vector<uint8_t>& message) const;
    // Caches a cacheable chunk under what it holds.
    void keep(DecodedChunk chunk, size_t bytes);

    std::unique_ptr<Connection> mConnection;
    std::string mHello;
    std::map<std::tuple<uint32_t, double, uint32_t>, DecodedChunk> mCache;
    std::map<std::tuple<uint32_t, double, uint32_t>, uint64_t> mCacheBytes;
    std::map<uint32_t, std::pair<uint32_t, double>> mViews;  // seq -> store, iso
    uint32_t mEvictSeq = 0;
    bool mDecode = true;
    std::chrono::steady_clock::time_point mSent;
};

}  // namespace vdiso::serve
