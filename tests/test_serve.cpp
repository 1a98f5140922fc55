// vdiso serve end to end over a real socket: frames against the library's extraction, frame
// coherence, cancellation, every refused message, the token, the files, concurrent clients,
// several stores and a store in a bucket. (Its messages alone: test_serve_messages.cpp; many
// viewers: test_serve_viewers.cpp; follow mode: test_serve_follow.cpp.)
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <future>
#include <thread>

#include <netinet/in.h>
#include <sys/resource.h>
#include <sys/socket.h>
#include <unistd.h>

#include <boost/asio/connect.hpp>
#include <boost/asio/ip/tcp.hpp>
#include <boost/beast/core.hpp>
#include <boost/beast/http.hpp>
#include <boost/beast/websocket.hpp>
#include <nlohmann/json.hpp>

#include "cache/brick_cache.h"
#include "core/camera.h"
#include "core/extract/extract_full.h"
#include "core/extract/extract_view.h"
#include "core/synth/synth.h"
#include "core/view_presets.h"
#include "io/store/brick_store.h"
#include "io/error.h"
#include "io/render/image_compare.h"
#include "io/render/renderer.h"
#include "io/store/store_writer.h"
#include "io/readers/volume_open.h"
#include "serve/chunk_codec.h"
#include "serve/frame_stream.h"
#include "serve/outbox.h"
#include "serve/protocol.h"
#include "serve/server.h"
#include "serve/viewer_client.h"
#include "serve/viewer_session.h"
#include "tests/extract_test_util.h"
#include "tests/loopback_servers.h"
#include "tests/serve_test_util.h"
#include "tests/test_util.h"

namespace vdiso {
namespace {

using namespace serve;
using test::presetFor;
using test::ServerFixture;
using test::viewOf;
using test::httpGet;
using test::writeWebRoot;

// ---------------------------------------------------------------------------------------------
// The server over a socket

// The library's streamed extraction for one camera with nothing held: what the first frame of
// a client must be (cacheable chunks: whole bricks; the rest: SAGE's own output).
struct LibraryFrame final : ViewStream {
    std::map<uint32_t, TriangleMesh> whole;
    TriangleMesh part;
    PointSet partPoints;
    bool beginBrick(int64_t, int level, double cellPixels, Use& use) override {
        use = sendsWhole(level, cellPixels) ? Use::Whole : Use::Part;
        return true;
    }
    void endBrick(int64_t brick, Use use, const TriangleMesh& mesh, const PointSet& points,
                  const TriangleMesh& seams) override {
        addPart(seams, PointSet{});  // the server sends them as transient geometry
        TriangleMesh local;
        local.positions = mesh.positions;
        local.normals = mesh.normals;
        for (const uint32_t v : mesh.indices) local.indices.push_back(v - mesh.firstVertex);
        if (use == Use::Whole) {
            whole[uint32_t(brick)] = std::move(local);
            return;
        }
        addPart(mesh, points);
    }
    void addPart(const TriangleMesh& mesh, const PointSet& points) {
        const uint32_t offset = uint32_t(part.positions.size());
        part.positions.insert(part.positions.end(), mesh.positions.begin(), mesh.positions.end());
        part.normals.insert(part.normals.end(), mesh.normals.begin(), mesh.normals.end());
        for (const uint32_t v : mesh.indices) part.indices.push_back(v - mesh.firstVertex + offset);
        partPoints.positions.insert(partPoints.positions.end(), points.positions.begin(), points.positions.end());
        partPoints.normals.insert(partPoints.normals.end(), points.normals.begin(), points.normals.end());
    }
};

// The triangles of a mesh after the wire's quantization in `box`, canonical and sorted.
std::vector<std::array<float, 9>> onTheWire(const TriangleMesh& mesh) {
    ChunkHeader h;
    return test::canonicalTriangles(decodeChunk(encodeChunk(h, mesh, PointSet{})).mesh);
}

// How much of the full surface's picture the frame's geometry reproduces.
double agreementWithFullSurface(const std::string& storePath, const Camera& camera,
                                const TriangleMesh& frame, const PointSet& points) {
    const BrickStoreReader store(storePath);
    BrickCache cache(store, uint64_t(64) << 20);
    TriangleMesh full;
    extractOctree(cache, {kHeadSkinIso, 4}, full);
    const RgbaImage reference = renderSurface(full, PointSet{}, camera).image;
    const RgbaImage ours = renderSurface(frame, points, camera).image;
    return compareImages(reference, ours).agreement();
}

TEST(ServeSession, FirstFrameIsTheLibrarysStreamedExtraction) {
    ServerFixture fixture;
    auto client = fixture.client();
    const nlohmann::json hello = nlohmann::json::parse(client->hello());
    ASSERT_EQ(hello["stores"].size(), 1u);
    EXPECT_EQ(hello["stores"][0]["name"], "head");
    EXPECT_EQ(hello["stores"][0]["iso"], kHeadSkinIso);
    EXPECT_EQ(hello["stores"][0]["histogram"]["counts"].size(), 256u);

    const Camera camera = presetFor(fixture.storePath, ViewPreset::Normal, 192);
    const ClientFrame frame = client->requestFrame(viewOf(camera, 1));
    ASSERT_EQ(frame.status, "complete") << frame.frameEnd;
    // The store has levels of detail: a coarse frame (8 px) came first, complete, with fewer
    // triangles, and the final frame (1 px, the default) after it.
    EXPECT_EQ(frame.coarseFrames, 1);
    EXPECT_GT(frame.coarseTriangles, 0u);
    EXPECT_LT(frame.coarseTriangles, nlohmann::json::parse(frame.frameEnd)["triangles"].get<uint64_t>());
    EXPECT_LE(frame.coarseCompleteSeconds, frame.completeSeconds);
    EXPECT_EQ(nlohmann::json::parse(frame.frameEnd)["final"], true);
    EXPECT_TRUE(frame.refs.empty());
    EXPECT_EQ(frame.missingRefs, 0u);
    ASSERT_FALSE(frame.chunks.empty());

    // The library, for the same camera.
    const BrickStoreReader store(fixture.storePath);
    BrickCache cache(store, uint64_t(64) << 20);
    LibraryFrame library;
    ViewExtractOptions options = ViewExtractOptions::sage(kHeadSkinIso);
    options.stream = &library;
    options.lodError = 1;  // the server's default
    TriangleMesh unused;
    PointSet unusedPoints;
    extractViewDependent(cache, camera, options, unused, unusedPoints);

    std::vector<uint32_t> expectedBricks;
    for (const auto& [brick, mesh] : library.whole) expectedBricks.push_back(brick);
    std::vector<uint32_t> bricks = frame.chunks;
    std::sort(bricks.begin(), bricks.end());
    EXPECT_EQ(bricks, expectedBricks);
    // Each chunk holds its brick's triangles (as the wire quantizes them).
    TriangleMesh assembled;
    PointSet points;
    for (const uint32_t b : frame.chunks) {
        ClientFrame one;
        one.store = 0;
        one.iso = kHeadSkinIso;
        one.chunks = {b};
        TriangleMesh chunk;
        PointSet none;
        client->assemble(one, chunk, none);
        ASSERT_TRUE(library.whole.contains(b));
        EXPECT_EQ(test::canonicalTriangles(chunk), onTheWire(library.whole[b])) << "brick " << b;
    }
    uint64_t transientTriangles = 0, transientPoints = 0;
    for (const DecodedChunk& c : frame.transient) {
        transientTriangles += c.mesh.triangleCount();
        transientPoints += c.points.size();
    }
    EXPECT_EQ(transientTriangles, library.part.triangleCount());
    EXPECT_EQ(transientPoints, library.partPoints.size());
    const nlohmann::json end = nlohmann::json::parse(frame.frameEnd);
    EXPECT_EQ(end["chunks"].get<uint64_t>(), frame.chunks.size() + frame.transient.size());
    EXPECT_EQ(end["bytes"].get<uint64_t>(), frame.binaryBytes);

    // And it looks like the full surface.
    client->assemble(frame, assembled, points);
    EXPECT_GT(agreementWithFullSurface(fixture.storePath, camera, assembled, points), 0.99);
}

TEST(ServeSession, NearbyCameraSendsOnlyMissingChunks) {
    ServerFixture fixture;
    auto client = fixture.client();
    const Camera first = presetFor(fixture.storePath, ViewPreset::Normal, 192);
    const ClientFrame a = client->requestFrame(viewOf(first, 1));
    ASSERT_EQ(a.status, "complete");
    const Camera second = presetFor(fixture.storePath, ViewPreset::Normal, 192, 10);
    const ClientFrame b = client->requestFrame(viewOf(second, 2));
    ASSERT_EQ(b.status, "complete") << b.frameEnd;
    // The first VIEW had a coarse frame before its final one; this one, of the same isovalue,
    // has its final one only when that final pass took at most SessionSettings::kQuickFinalPass
    // (known when the whole of the first frame did: its serverMs counts from the VIEW's arrival;
    // about 10 ms here, so only a stalled machine leaves it unknown).
    EXPECT_EQ(a.coarseFrames, 1);
    const double firstMs = nlohmann::json::parse(a.frameEnd)["serverMs"].get<double>();
    if (firstMs <= double(serve::SessionSettings::kQuickFinalPass.count())) {
        EXPECT_EQ(b.coarseFrames, 0) << "the first frame took " << firstMs << " ms";
    }
    EXPECT_EQ(nlohmann::json::parse(b.frameEnd)["final"], true);
    EXPECT_EQ(b.missingRefs, 0u);
    EXPECT_FALSE(b.refs.empty());
    for (const uint32_t brick : b.chunks)  // nothing held is sent again
        EXPECT_TRUE(std::find(a.chunks.begin(), a.chunks.end(), brick) == a.chunks.end()) << brick;
    for (const uint32_t brick : b.refs) EXPECT_TRUE(client->holds(0, kHeadSkinIso, brick)) << brick;
    EXPECT_LT(b.binaryBytes * 2, a.binaryBytes);
    TriangleMesh mesh;
    PointSet points;
    client->assemble(b, mesh, points);
    EXPECT_GT(agreementWithFullSurface(fixture.storePath, second, mesh, points), 0.99);

    // Evicted chunks are sent again, not referred to.
    const std::vector<uint32_t> dropped(b.refs.begin(), b.refs.begin() + std::min<size_t>(5, b.refs.size()));
    client->evict(0, kHeadSkinIso, dropped);
    const ClientFrame c = client->requestFrame(viewOf(second, 3));
    ASSERT_EQ(c.status, "complete");
    EXPECT_EQ(c.missingRefs, 0u);
    for (const uint32_t brick : dropped)
        EXPECT_TRUE(std::find(c.chunks.begin(), c.chunks.end(), brick) != c.chunks.end()) << brick;

    // A new isovalue shares nothing with the old one.
    const ClientFrame d = client->requestFrame(viewOf(second, 4, kHeadBoneIso));
    ASSERT_EQ(d.status, "complete");
    EXPECT_TRUE(d.refs.empty());
    EXPECT_EQ(d.coarseFrames, 1);  // the viewer holds no surface of it: a coarse one first
}

TEST(ServeSession, TwoStripsSendEachBrickOnce) {
    ServerFixture fixture(uint64_t(256) << 20, 2);
    auto client = fixture.client();
    for (uint32_t seq = 1; seq <= 3; ++seq) {
        const Camera camera = presetFor(fixture.storePath, ViewPreset::Normal, 192, 10.0 * (seq - 1));
        const ClientFrame f = client->requestFrame(viewOf(camera, seq));
        ASSERT_EQ(f.status, "complete") << f.frameEnd;
        EXPECT_EQ(f.missingRefs, 0u);
        std::vector<uint32_t> named = f.chunks;
        named.insert(named.end(), f.refs.begin(), f.refs.end());
        std::sort(named.begin(), named.end());
        EXPECT_TRUE(std::adjacent_find(named.begin(), named.end()) == named.end()) << "a brick named twice";
        TriangleMesh mesh;
        PointSet points;
        client->assemble(f, mesh, points);
        EXPECT_GT(agreementWithFullSurface(fixture.storePath, camera, mesh, points), 0.99);
    }
}

TEST(ServeSession, NewerCameraAbandonsTheFrameInFlight) {
    ServerFixture fixture(uint64_t(256) << 20, 1, {160, 160, 160});
    auto client = fixture.client();
    const Camera slow = presetFor(fixture.storePath, ViewPreset::Closeup, 1024);
    const Camera other = presetFor(fixture.storePath, ViewPreset::Normal, 128, 90);
    client->sendView(viewOf(slow, 1));
    client->sendView(viewOf(other, 2));
    // Frame 1 never completes: it was abandoned at a brick, or never started.
    const ClientFrame b = client->readFrame(2);
    EXPECT_EQ(b.status, "complete");
    TriangleMesh mesh;
    PointSet points;
    client->assemble(b, mesh, points);
    EXPECT_GT(mesh.triangleCount(), 0u);

    // The frame in flight while the camera keeps moving: every frame but the last superseded,
    // the last complete.
    for (uint32_t seq = 3; seq < 8; ++seq) client->sendView(viewOf(presetFor(fixture.storePath, ViewPreset::Closeup, 1024, seq), seq));
    const ClientFrame last = client->readFrame(7);
    EXPECT_EQ(last.status, "complete");
    EXPECT_EQ(last.missingRefs, 0u);
    TriangleMesh lastMesh;
    PointSet lastPoints;
    client->assemble(last, lastMesh, lastPoints);
    EXPECT_GT(agreementWithFullSurface(fixture.storePath, presetFor(fixture.storePath, ViewPreset::Closeup, 1024, 7),
                                       lastMesh, lastPoints),
              0.99);
}

TEST(ServeSession, BadMessagesGetAnErrorAndTheConnectionStays) {
    ServerFixture fixture;
    auto client = fixture.client();
    auto expectError = [&](const std::vector<uint8_t>& bytes, bool text, const std::string& words) {
        client->sendRaw(bytes, text);
        const std::string reply = client->readText();
        const nlohmann::json j = nlohmann::json::parse(reply);
        EXPECT_EQ(j["type"], "error") << reply;
        EXPECT_NE(j["message"].get<std::string>().find(words), std::string::npos) << reply;
        return j;
    };
    const Camera camera = presetFor(fixture.storePath, ViewPreset::Normal, 128);
    ViewMessage v = viewOf(camera, 1);
    uint32_t oddSeq = 0;
    expectError({'{', 'x'}, true, "text message");
    expectError({1, 2, 3}, false, "shorter than a header");
    expectError({42, 1, 0, 0, 0, 0}, false, "unknown message type");
    v.eye.y = NAN;
    v.seq = 42;
    EXPECT_EQ(expectError(encodeView(v), false, "finite")["seq"], 42);  // names the refused VIEW
    v = viewOf(camera, 1);
    v.eye.x = INFINITY;
    expectError(encodeView(v), false, "finite");
    v = viewOf(camera, 1);
    v.eye = v.target;
    expectError(encodeView(v), false, "eye and target");
    v = viewOf(camera, 1);
    v.width = 8193;
    expectError(encodeView(v), false, "width and height");
    v = viewOf(camera, 1);
    v.store = 3;
    expectError(encodeView(v), false, "unknown store");
    v = viewOf(camera, 1);
    v.iso = 1e9;
    expectError(encodeView(v), false, "outside");
    std::vector<uint8_t> truncated = encodeView(viewOf(camera, 1));
    truncated.resize(60);
    expectError(truncated, false, "bytes, expected 112");
    std::vector<uint8_t> huge(kMaxClientMessageBytes + 100000, 0);
    huge[0] = 1, huge[1] = 1;
    expectError(huge, false, "above the limit");
    EvictMessage e;
    e.store = 9;
    expectError(encodeEvict(e), false, "unknown store");

    // Cameras at the edge of what doubles hold (found by fuzz_protocol: NaN and huge screen
    // boxes reached int conversions): each is refused or gets a frame, nothing crashes.
    for (const auto& [eye, fov] : {std::pair{glm::dvec3(1e300, -1e300, 1e300), 30.0},
                                   std::pair{glm::dvec3(1e150, -1e150, 1e150), 30.0},
                                   std::pair{camera.eye, 1e-300}, std::pair{camera.eye, 179.9999999}}) {
        ViewMessage odd = viewOf(camera, ++oddSeq);
        odd.eye = eye;
        odd.fovYDegrees = fov;
        client->sendView(odd);
        while (true) {
            const nlohmann::json j = nlohmann::json::parse(client->readText());
            if (j["type"] == "error" && j.value("seq", -1) == int(odd.seq)) break;
            if (j["type"] == "frameEnd" && j["frame"] == odd.seq) {
                EXPECT_NE(j["status"], "error") << j;
                break;
            }
        }
    }

    // Still serving: a good view gets its frame, and a stale sequence number is refused.
    const ClientFrame frame = client->requestFrame(viewOf(camera, 5 + oddSeq));
    EXPECT_EQ(frame.status, "complete");
    expectError(encodeView(viewOf(camera, 5 + oddSeq)), false, "seq");
}

TEST(ServeHttp, TokenIsRequiredAndOnlyTheViewersFilesAreServed) {
    ServerFixture fixture;
    const uint16_t port = fixture.server->port();
    const std::string token = fixture.server->token();
    EXPECT_EQ(token.size(), 32u);
    EXPECT_NE(fixture.server->url().find("?token=" + token), std::string::npos);
    EXPECT_EQ(httpGet(port, "/", ""), 403);
    EXPECT_EQ(httpGet(port, "/?token=wrong", ""), 403);
    EXPECT_EQ(httpGet(port, "/src/main.js", ""), 403);
    std::string body, cookie;
    EXPECT_EQ(httpGet(port, "/?token=" + token, "", &body, &cookie), 200);
    EXPECT_NE(body.find("viewer"), std::string::npos);
    EXPECT_NE(cookie.find("vdiso_token_" + std::to_string(port) + "=" + token), std::string::npos);
    EXPECT_NE(cookie.find("HttpOnly"), std::string::npos);
    const std::string jar = "vdiso_token_" + std::to_string(port) + "=" + token;
    EXPECT_EQ(httpGet(port, "/src/main.js", jar, &body), 200);
    EXPECT_NE(body.find("main"), std::string::npos);
    EXPECT_EQ(httpGet(port, "/vendor/three.module.js", jar), 200);
    EXPECT_EQ(httpGet(port, "/src/main.js", "vdiso_token_" + std::to_string(port) + "=nope"), 403);
    EXPECT_EQ(httpGet(port, "/src/main.js", "vdiso_token=" + token), 403);  // another port's cookie
    for (const char* path : {"/../secret.txt", "/src/../../secret.txt", "/%2e%2e/secret.txt", "/src/",
                             "/src", "/node_modules/three/package.json", "/vendor/", "/web/index.html",
                             "//etc/passwd", "/index.html/../../secret.txt"})
        EXPECT_EQ(httpGet(port, path, jar), 404) << path;
    // The WebSocket needs the token too, and the server's own page as its origin.
    EXPECT_THROW(ViewerClient("127.0.0.1", port, "wrong"), IoError);
    auto handshake = [&](const std::string& origin) {
        namespace websocket = boost::beast::websocket;
        boost::asio::io_context ioc;
        boost::asio::ip::tcp::resolver resolver(ioc);
        websocket::stream<boost::asio::ip::tcp::socket> ws(ioc);
        boost::asio::connect(ws.next_layer(), resolver.resolve("127.0.0.1", std::to_string(port)));
        ws.set_option(websocket::stream_base::decorator(
            [&](websocket::request_type& r) { r.set(boost::beast::http::field::origin, origin); }));
        boost::beast::error_code error;
        ws.handshake("127.0.0.1:" + std::to_string(port), "/ws?token=" + token, error);
        return !error;
    };
    EXPECT_TRUE(handshake("http://127.0.0.1:" + std::to_string(port)));
    EXPECT_FALSE(handshake("http://evil.example"));
    EXPECT_GE(fixture.server->counters().httpRefused, 4u);
}

TEST(ServeSession, EightClientsShareOneSmallCache) {
    // A cache of 40 bricks of a 729-brick volume: clients take turns through the frame gate,
    // and every frame still completes.
    const uint64_t brickBytes = 11 * 11 * 11 * 2;
    ServerFixture fixture(40 * brickBytes, 1);
    const Camera camera = presetFor(fixture.storePath, ViewPreset::Normal, 160);
    auto reference = fixture.client();
    const ClientFrame alone = reference->requestFrame(viewOf(camera, 1));
    ASSERT_EQ(alone.status, "complete");
    TriangleMesh aloneMesh;
    PointSet alonePoints;
    reference->assemble(alone, aloneMesh, alonePoints);

    std::vector<std::future<std::string>> results;
    for (int k = 0; k < 8; ++k)
        results.push_back(std::async(std::launch::async, [&, k]() -> std::string {
            auto client = fixture.client();
            std::string failures;
            for (uint32_t seq = 1; seq <= 3; ++seq) {
                const Camera c = seq == 3 ? camera : presetFor(fixture.storePath, ViewPreset::Normal, 160, 30 * k + 10 * seq);
                const ClientFrame f = client->requestFrame(viewOf(c, seq));
                if (f.status != "complete") failures += "client " + std::to_string(k) + " frame " + std::to_string(seq) + ": " + f.frameEnd + "\n";
                if (f.missingRefs) failures += "missing refs\n";
                if (seq == 3) {
                    TriangleMesh mesh;
                    PointSet points;
                    client->assemble(f, mesh, points);
                    if (test::canonicalTriangles(mesh) != test::canonicalTriangles(aloneMesh))
                        failures += "client " + std::to_string(k) + ": frame differs from a lone client's\n";
                }
            }
            return failures;
        }));
    for (auto& r : results) EXPECT_EQ(r.get(), "");
    EXPECT_GE(fixture.server->counters().sessionsOpened, 9u);
}

TEST(ServeSession, DisconnectMidFrameFreesTheSession) {
    ServerFixture fixture(uint64_t(256) << 20, 1, {160, 160, 160});
    {
        auto client = fixture.client();
        client->sendView(viewOf(presetFor(fixture.storePath, ViewPreset::Closeup, 2048), 1));
        client->close();
    }
    // The session goes away with its work, and the server serves the next client.
    for (int i = 0; i < 200 && fixture.server->counters().sessionsOpen > 0; ++i)
        std::this_thread::sleep_for(std::chrono::milliseconds(10));
    EXPECT_EQ(fixture.server->counters().sessionsOpen, 0u);
    auto next = fixture.client();
    EXPECT_EQ(next->requestFrame(viewOf(presetFor(fixture.storePath, ViewPreset::Normal, 128), 1)).status, "complete");
}

TEST(ServeServer, OffersSeveralStores) {
    test::ScratchDir dir;
    writeWebRoot(dir);
    SynthParams head;
    head.dims = {40, 40, 40};
    writeBrickStore(*openSynthVolume(head), dir.file("head.vdiso"), StoreWriteOptions{});
    SynthParams turbulence;
    turbulence.kind = SynthKind::Turbulence;
    turbulence.dims = {36, 36, 36};
    turbulence.type = ScalarType::F32;
    writeBrickStore(*openSynthVolume(turbulence), dir.file("turbulence.vdiso"), StoreWriteOptions{});
    ServeOptions s;
    s.port = 0;
    s.stores = {dir.file("head.vdiso"), dir.file("turbulence.vdiso")};
    s.webRoot = dir.file("web");
    Server server(s);
    std::thread serving([&] { server.run(); });
    {
        ViewerClient client("127.0.0.1", server.port(), server.token());
        const nlohmann::json stores = nlohmann::json::parse(client.hello())["stores"];
        ASSERT_EQ(stores.size(), 2u);
        EXPECT_EQ(stores[1]["name"], "turbulence");
        EXPECT_EQ(stores[1]["type"], "f32");
        // Without --iso each store starts at Otsu's threshold of its own values.
        const double iso = stores[1]["iso"].get<double>();
        EXPECT_GT(iso, stores[1]["valueMin"].get<double>());
        EXPECT_LT(iso, stores[1]["valueMax"].get<double>());
        Camera c = presetCamera(ViewPreset::Normal, {0, 0, 0}, {35, 35, 35}, 128, 128);
        const ClientFrame f = client.requestFrame(viewMessage(c, 1, 1, iso));
        EXPECT_EQ(f.status, "complete") << f.frameEnd;
        TriangleMesh mesh;
        PointSet points;
        client.assemble(f, mesh, points);
        EXPECT_GT(mesh.triangleCount(), 0u);
    }
    server.stop();
    serving.join();
}

// A store in a bucket is served as the local file is: the first frame's geometry is the local
// server's. A frame whose bricks cannot be fetched ends in an error naming the URL and the
// server stays up: once the bucket answers again, the next frame completes.
TEST(ServeServer, StoreInABucket) {
    test::ScratchDir dir;
    writeWebRoot(dir);
    std::filesystem::create_directories(dir.path() / "bkt");
    SynthParams p;
    p.dims = {72, 72, 72};
    StoreWriteOptions o;
    o.brickSize = 8;
    const std::string local = dir.file("bkt/head.vdiso");
    writeBrickStore(*openSynthVolume(p), local, o);
    test::LoopbackServer s3 = test::startS3(dir.path().string(), dir.file("s3.log"), {"--public", "bkt"});
    auto serve = [&](const std::string& store) {
        ServeOptions s;
        s.port = 0;
        s.stores = {store};
        s.webRoot = dir.file("web");
        s.iso = kHeadSkinIso;
        s.remote.s3Endpoint = "http://127.0.0.1:" + std::to_string(s3.port());
        s.remote.anonymous = true;
        s.remote.attempts = 2;
        return std::make_unique<Server>(s);
    };
    auto frame = [](Server& server, const Camera& camera, uint32_t seq, TriangleMesh& mesh) {
        ViewerClient client("127.0.0.1", server.port(), server.token());
        client.hello();
        const ClientFrame f = client.requestFrame(viewOf(camera, seq));
        PointSet points;
        if (f.status == "complete") client.assemble(f, mesh, points);
        return f;
    };
    const Camera normal = presetFor(local, ViewPreset::Normal, 128);
    const Camera behind = presetFor(local, ViewPreset::Normal, 128, 180);
    TriangleMesh want;
    {
        auto server = serve(local);
        std::thread serving([&] { server->run(); });
        EXPECT_EQ(frame(*server, normal, 1, want).status, "complete");
        server->stop();
        serving.join();
    }
    ASSERT_GT(want.triangleCount(), 0u);
    auto server = serve("s3://bkt/head.vdiso");
    std::thread serving([&] { server->run(); });
    TriangleMesh got;
    ClientFrame f = frame(*server, normal, 1, got);
    EXPECT_EQ(f.status, "complete") << f.frameEnd;
    EXPECT_EQ(test::canonicalTriangles(got), test::canonicalTriangles(want));

    // Every GET answered 500: the frame of the back of the head needs bricks not yet fetched (a
    // closeup from there has its eye inside the volume, and reads nothing behind it).
    ASSERT_TRUE(test::controlS3(s3.port(), R"([{"op":"fault","action":"status","status":500,"count":-1}])"));
    TriangleMesh none;
    f = frame(*server, behind, 2, none);
    EXPECT_EQ(f.status, "error") << f.frameEnd;
    ASSERT_EQ(f.errors.size(), 1u);
    EXPECT_NE(f.errors[0].find("s3://bkt/head.vdiso: HTTP 500"), std::string::npos) << f.errors[0];
    ASSERT_TRUE(test::controlS3(s3.port(), R"([{"op":"clear_faults"}])"));
    f = frame(*server, behind, 3, none);
    EXPECT_EQ(f.status, "complete") << f.frameEnd;
    EXPECT_GT(none.triangleCount(), 0u);
    server->stop();
    serving.join();
}

TEST(ServeServer, RefusesWhatItCannotServe) {
    test::ScratchDir dir;
    ServeOptions s;
    s.port = 0;
    s.stores = {dir.file("missing.vdiso")};
    s.webRoot = dir.file("web");
    EXPECT_THROW(Server{s}, IoError);
    writeWebRoot(dir);
    SynthParams p;
    p.dims = {20, 20, 20};
    writeBrickStore(*openSynthVolume(p), dir.file("a.vdiso"), StoreWriteOptions{});
    s.stores = {dir.file("a.vdiso")};
    s.webRoot = dir.file("nothing-here");
    try {
        Server server(s);
        ADD_FAILURE() << "a missing viewer folder was accepted";
    } catch (const IoError& e) {
        EXPECT_NE(std::string(e.what()).find("index.html"), std::string::npos) << e.what();
    }
    s.webRoot = dir.file("web");
    s.iso = 1e9;
    EXPECT_THROW(Server{s}, IoError);
    s.iso.reset();
    s.stores = {dir.file("a.vdiso"), dir.file("a.vdiso")};
    EXPECT_THROW(Server{s}, IoError);  // two stores of one name
    s.stores = {dir.file("a.vdiso")};
    s.host = "not-an-address";
    EXPECT_THROW(Server{s}, IoError);
    s.host = "127.0.0.1";
    SynthParams bigger;
    bigger.dims = {200, 200, 40};
    StoreWriteOptions eight;
    eight.brickSize = 8;
    writeBrickStore(*openSynthVolume(bigger), dir.file("b.vdiso"), eight);
    s.stores = {dir.file("b.vdiso")};
    s.cacheBytes = 10 * 11 * 11 * 11 * 2;  // 10 bricks: less than a frame pins
    try {
        Server server(s);
        ADD_FAILURE() << "a cache smaller than a frame's pins was accepted";
    } catch (const IoError& e) {
        EXPECT_NE(std::string(e.what()).find("cannot hold what one frame pins (16 bricks"), std::string::npos)
            << e.what();
        EXPECT_NE(dynamic_cast<const CacheBudgetError*>(&e), nullptr) << e.what();
    }
}

}  // namespace
}  // namespace vdiso
