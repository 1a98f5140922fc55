// vdiso serve's tests' common parts: a server on an ephemeral port over a generated head, its
// cameras and VIEWs, and one HTTP request.
#pragma once

#include <cstdint>
#include <memory>
#include <sys/types.h>
#include <string>
#include <thread>
#include <vector>

#include "core/camera.h"
#include "core/synth/synth.h"
#include "core/view_presets.h"
#include "serve/protocol.h"
#include "serve/server.h"
#include "serve/viewer_client.h"
#include "tests/extract_test_util.h"
#include "tests/test_util.h"

namespace vdiso::test {

// A fake viewer folder in dir/web: the server needs the page's files to exist, not to be the
// real page (and dir/secret.txt, which must never be served).
void writeWebRoot(const ScratchDir& dir);

// A generated head in a store of 8-cell bricks, and a server on an ephemeral port.
struct ServerFixture {
    ScratchDir dir;
    std::string storePath;
    std::unique_ptr<serve::Server> server;
    std::thread thread;

    explicit ServerFixture(uint64_t cacheBytes = uint64_t(256) << 20, int threads = 1,
                           const Dims3& dims = {72, 72, 72}, int maxViewers = 0, double writeTimeout = 30,
                           uint64_t chunkCacheBytes = uint64_t(256) << 20, size_t outboxBytes = size_t(32) << 20);
    ~ServerFixture();
    std::unique_ptr<serve::ViewerClient> client(const std::string& query = "");
};

// The store's preset camera, turned about z by `turnDegrees`, clip planes fitted.
Camera presetFor(const std::string& storePath, ViewPreset preset, int size, double turnDegrees = 0);
inline serve::ViewMessage viewOf(const Camera& c, uint32_t seq, double iso = kHeadSkinIso) {
    return serve::viewMessage(c, seq, 0, iso);
}

// One HTTP GET; returns the status code, with the body and the Set-Cookie header.
int httpGet(uint16_t port, const std::string& target, const std::string& cookie, std::string* body = nullptr,
            std::string* setCookie = nullptr);

// `vdiso serve ARGS` in a child process, its port read from the URL it prints; killed
// (SIGKILL) when this goes unless wait() took it. `inChild` runs between fork and exec
// (async-signal-safe calls only; a non-zero return ends the child with 126).
class ServeProcess {
public:
    ServeProcess(const std::vector<std::string>& args, int (*inChild)() = nullptr);
    ~ServeProcess();
    ServeProcess(const ServeProcess&) = delete;
    ServeProcess& operator=(const ServeProcess&) = delete;
    // 0 when the server did not print its URL (it failed to start).
    uint16_t port() const { return mPort; }
    pid_t pid() const { return mPid; }
    // Waits for the process to end; its wait status.
    int wait();

private:
    pid_t mPid = -1;
    uint16_t mPort = 0;
};

// A client frame as RFC 6455 wants it: FIN, the opcode, the masked length and payload.
std::string maskedFrame(uint8_t opcode, const std::vector<uint8_t>& payload);
// A WebSocket client over a raw socket (with a small receive buffer unless `smallBuffer` is
// false), upgraded, its answer left unread: a client that will not read, or that reads only
// what the caller recv()s. -1 when it cannot connect.
int unreadingClient(const ServerFixture& fixture, bool smallBuffer = true);

}  // namespace vdiso::test
