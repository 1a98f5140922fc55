// The server's protocol: every client message through a live ViewerSession over a small store
// (validation, then frames extracted for whatever camera passes it), and the client-side
// decoders of the server's messages (CHUNK, REFS).
#include <cstring>
#include <filesystem>
#include <chrono>
#include <memory>
#include <thread>

#include <unistd.h>

#include "core/synth/synth.h"
#include "fuzz/fuzz_input.h"
#include "io/store/store_writer.h"
#include "io/readers/volume_open.h"
#include "serve/chunk_codec.h"
#include "serve/protocol.h"
#include "serve/store_catalog.h"
#include "serve/viewer_session.h"

namespace {

struct World {
    std::filesystem::path dir;
    std::unique_ptr<vdiso::serve::StoreCatalog> stores;
    std::unique_ptr<vdiso::serve::FramePool> pool;
    vdiso::serve::SessionDirectory directory;
    std::unique_ptr<vdiso::serve::ViewerSession> session;
    uint32_t seq = 0;

    World() {
        dir = std::filesystem::temp_directory_path() / ("vdiso-fuzz-protocol-" + std::to_string(::getpid()));
        std::filesystem::create_directories(dir);
        vdiso::SynthParams p;
        p.dims = {24, 24, 24};
        vdiso::StoreWriteOptions o;
        o.brickSize = 8;
        vdiso::writeBrickStore(*vdiso::openSynthVolume(p), (dir / "head.vdiso").string(), o);
        stores = std::make_unique<vdiso::serve::StoreCatalog>(
            std::vector<std::string>{(dir / "head.vdiso").string()}, uint64_t(64) << 20, uint64_t(16) << 20,
            std::nullopt);
        pool = std::make_unique<vdiso::serve::FramePool>(2);
        session = std::make_unique<vdiso::serve::ViewerSession>(*stores, vdiso::serve::SessionSettings{}, *pool, directory, [] {});
        session->start();
    }
    ~World() {
        session.reset();
        std::error_code ignored;
        std::filesystem::remove_all(dir, ignored);
    }
};

World& world() {
    static World w;
    return w;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    using namespace vdiso::serve;
    World& w = world();
    if (size == 0) return 0;
    const bool text = data[0] & 1;
    std::vector<uint8_t> message(data + 1, data + size);
    // A VIEW-shaped message gets the next seq, so that it is not refused for its order alone.
    if (!text && message.size() == kViewMessageBytes && message[0] == uint8_t(MessageType::View)) {
        ++w.seq;
        std::memcpy(message.data() + 4, &w.seq, 4);
    }
    w.session->onMessage(message, text);
    // An accepted VIEW is followed to its frame's end, so that what the frame does is charged
    // to this input (the worker thread extracts it); a refused one is answered at once.
    bool waitForFrame = !text && message.size() == kViewMessageBytes && message[0] == uint8_t(MessageType::View);
    bool answered = false;
    while (true) {
        const std::optional<OutMessage> m = w.session->nextToWrite();
        if (!m) {
            if (!waitForFrame) break;
            std::this_thread::sleep_for(std::chrono::microseconds(50));
            continue;
        }
        const std::string reply(m->bytes->begin(), m->bytes->end());
        if (m->text && reply.find("\"error\"") != std::string::npos && !answered) waitForFrame = false;
        if (m->text && reply.find("\"frameEnd\"") != std::string::npos) waitForFrame = false;
        answered = true;
    }
    // The client's decoders, on the same bytes.
    vdiso::fuzz::expectAnswer([&] { decodeChunk(message); });
    vdiso::fuzz::expectAnswer([&] {
        uint32_t frame;
        decodeRefs(message, frame);
    });
    return 0;
}
