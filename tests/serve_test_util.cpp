#include "tests/serve_test_util.h"

#include <cmath>
#include <csignal>
#include <cstring>

#include <netinet/in.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <unistd.h>
#include <filesystem>

#include <boost/asio/ip/tcp.hpp>
#include <boost/beast/core.hpp>
#include <boost/beast/http.hpp>

#include "core/view_presets.h"
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

ServeProcess::ServeProcess(const std::vector<std::string>& args, int (*inChild)()) {
    std::vector<std::string> argv = {VDISO_BINARY, "serve"};
    argv.insert(argv.end(), args.begin(), args.end());
    std::vector<char*> pointers;
    for (std::string& a : argv) pointers.push_back(a.data());
    pointers.push_back(nullptr);
    int out[2];
    if (::pipe(out) != 0) return;
    mPid = ::fork();
    if (mPid < 0) return;
    if (mPid == 0) {  // only async-signal-safe calls until exec
        ::dup2(out[1], 1);
        ::close(out[0]);
        if (inChild && inChild() != 0) ::_exit(126);
        ::execv(VDISO_BINARY, pointers.data());
        ::_exit(127);
    }
    ::close(out[1]);
    // "vdiso serve: open http://127.0.0.1:PORT/?token=..."
    std::string line;
    char c;
    while (line.find('\n') == std::string::npos && ::read(out[0], &c, 1) == 1) line += c;
    ::close(out[0]);
    const size_t at = line.find("127.0.0.1:");
    if (at != std::string::npos) mPort = uint16_t(std::stoi(line.substr(at + 10)));
}

ServeProcess::~ServeProcess() {
    if (mPid <= 0) return;
    ::kill(mPid, SIGKILL);
    ::waitpid(mPid, nullptr, 0);
}

int ServeProcess::wait() {
    int status = 0;
    ::waitpid(mPid, &status, 0);
    mPid = -1;
    return status;
}

// A client frame as RFC 6455 wants it: FIN, the opcode, the masked length and payload.
std::string maskedFrame(uint8_t opcode, const std::vector<uint8_t>& payload) {
    std::string f;
    f += char(0x80 | opcode);
    const size_t n = payload.size();
    if (n < 126) {
        f += char(0x80 | n);
    } else {
        f += char(0x80 | 126);
        f += char(n >> 8);
        f += char(n & 255);
    }
    const uint8_t mask[4] = {0x12, 0x34, 0x56, 0x78};
    for (uint8_t m : mask) f += char(m);
    for (size_t i = 0; i < n; ++i) f += char(payload[i] ^ mask[i % 4]);
    return f;
}

// A WebSocket client over a raw socket with a small receive buffer, upgraded (its answer left
// unread): a client that will not read. -1 when it cannot connect.
int unreadingClient(const ServerFixture& fixture, bool smallBuffer) {
    const uint16_t port = fixture.server->port();
    const int fd = socket(AF_INET, SOCK_STREAM, 0);
    if (fd < 0) return -1;
    const int small = 4096;
    if (smallBuffer) setsockopt(fd, SOL_SOCKET, SO_RCVBUF, &small, sizeof small);
    sockaddr_in address{};
    address.sin_family = AF_INET;
    address.sin_port = htons(port);
    address.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    const std::string host = "127.0.0.1:" + std::to_string(port);
    const std::string upgrade = "GET /ws?token=" + fixture.server->token() + " HTTP/1.1\r\nHost: " + host +
                                "\r\nUpgrade: websocket\r\nConnection: Upgrade\r\nSec-WebSocket-Key: dGhlIHNhbXBsZSBub25jZQ==\r\n"
                                "Sec-WebSocket-Version: 13\r\nOrigin: http://" + host + "\r\n\r\n";
    if (connect(fd, reinterpret_cast<sockaddr*>(&address), sizeof address) != 0 ||
        send(fd, upgrade.data(), upgrade.size(), 0) != ssize_t(upgrade.size())) {
        close(fd);
        return -1;
    }
    return fd;
}

}  // namespace vdiso::test
