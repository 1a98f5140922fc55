// vdiso serve's tests' common parts: a server on an ephemeral port over a generated head, its
// cameras and VIEWs, and one HTTP request.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <thread>

#include "core/camera.h"
#include "core/synth/synth.h"
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

}  // namespace vdiso::test
