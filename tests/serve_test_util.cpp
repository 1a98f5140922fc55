#include "tests/serve_test_util.h"

#include <cmath>
#include <filesystem>

#include <boost/asio/ip/tcp.hpp>
#include <boost/beast/core.hpp>
#include <boost/beast/http.hpp>

#include "io/readers/volume_open.h"
#include "io/store/brick_store.h"
#include "io/store/store_writer.h"

namespace vdiso::test {

// A fake viewer folder: the server needs the page's files to exist, not to be the real page.
void writeWebRoot(const ScratchDir& dir) {
    namespace fs = std::filesystem;
    const fs::path root = dir.path() / "web";
    for (const char* d : {"src", "node_modules/three/build", "node_modules/three/examples/jsm/controls",
                          "node_modules/meshoptimizer"})
        fs::create_directories(root / d);
    writeFile((root / "index.html").string(), "<!doctype html><title>viewer</title>");
    writeFile((root / "src/main.js").string(), "export const main = 1;\n");
    writeFile((root / "node_modules/three/build/three.module.js").string(), "export {};\n");
    writeFile((root / "node_modules/three/examples/jsm/controls/OrbitControls.js").string(), "export {};\n");
    writeFile((root / "node_modules/meshoptimizer/meshopt_decoder.mjs").string(), "export {};\n");
    writeFile((root / "node_modules/three/package.json").string(), "{}");
    writeFile((dir.path() / "secret.txt").string(), "not for the web");
}

ServerFixture::ServerFixture(uint64_t cacheBytes, int threads, const Dims3& dims, int maxViewers, double writeTimeout,
                             uint64_t chunkCacheBytes, size_t outboxBytes) {
    SynthParams p;
    p.kind = SynthKind::Head;
    p.dims = dims;
    StoreWriteOptions o;
    o.brickSize = 8;
    storePath = dir.file("head.vdiso");
    writeBrickStore(*openSynthVolume(p), storePath, o);
    writeWebRoot(dir);
    serve::ServeOptions s;
    s.stores = {storePath};
    s.port = 0;
    s.cacheBytes = cacheBytes;
    s.threads = threads;
    s.webRoot = dir.file("web");
    s.iso = kHeadSkinIso;
    s.maxViewers = maxViewers;
    s.writeTimeoutSeconds = writeTimeout;
    s.chunkCacheBytes = chunkCacheBytes;
    s.outboxBytes = outboxBytes;
    server = std::make_unique<serve::Server>(s);
    thread = std::thread([this] { server->run(); });
}

ServerFixture::~ServerFixture() {
    server->stop();
    thread.join();
}

std::unique_ptr<serve::ViewerClient> ServerFixture::client(const std::string& query) {
    return std::make_unique<serve::ViewerClient>("127.0.0.1", server->port(), server->token(), query);
}

Camera presetFor(const std::string& storePath, ViewPreset preset, int size, double turnDegrees) {
    const BrickStoreReader store(storePath);
    const VolumeInfo& v = store.volume();
    std::vector<Camera> orbit = orbitCameras(preset, v.origin, v.worldMax(), size, size, 36);
    Camera c = orbit[0];
    if (turnDegrees != 0) {
        const double a = turnDegrees * M_PI / 180;
        const glm::dvec3 d = c.eye - c.target;
        c.eye = c.target + glm::dvec3(d.x * std::cos(a) - d.y * std::sin(a), d.x * std::sin(a) + d.y * std::cos(a), d.z);
    }
    fitClipPlanes(c, v.origin, v.worldMax());
    return c;
}

int httpGet(uint16_t port, const std::string& target, const std::string& cookie, std::string* body,
            std::string* setCookie) {
    namespace beast = boost::beast;
    namespace http = beast::http;
    boost::asio::io_context ioc;
    boost::asio::ip::tcp::resolver resolver(ioc);
    beast::tcp_stream stream(ioc);
    stream.connect(resolver.resolve("127.0.0.1", std::to_string(port)));
    http::request<http::string_body> request{http::verb::get, target, 11};
    request.set(http::field::host, "127.0.0.1");
    if (!cookie.empty()) request.set(http::field::cookie, cookie);
    http::write(stream, request);
    beast::flat_buffer buffer;
    http::response<http::string_body> response;
    http::read(stream, buffer, response);
    if (body) *body = response.body();
    if (setCookie) *setCookie = std::string(response[http::field::set_cookie]);
    beast::error_code ignored;
    stream.socket().shutdown(boost::asio::ip::tcp::socket::shutdown_both, ignored);
    return int(response.result_int());
}

}  // namespace vdiso::test
