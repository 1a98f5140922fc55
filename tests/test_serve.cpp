// vdiso serve: the protocol's messages, the chunk codec, the outbox, and the server end to end
// over a real socket (frames against the library's extraction, frame coherence, cancellation,
// every refused message, the token, the files, concurrent clients).
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

TEST(ServeChunkCodec, CountsBeyondTheirBytesAreRefusedBeforeAllocating) {
    // Found by fuzz_protocol: a small CHUNK announcing 0x7fffe00f vertices made the decoder ask
    // for 34 GB before the vertex codec saw that 40 bytes cannot hold them.
    TriangleMesh mesh;
    mesh.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
    mesh.normals = {{0, 0, 1}, {0, 0, 1}, {0, 0, 1}};
    mesh.indices = {0, 1, 2};
    PointSet points;
    points.positions = {{1, 2, 3}};
    points.normals = {{0, 0, 1}};
    const std::vector<uint8_t> message = encodeChunk(ChunkHeader{}, mesh, points);
    for (const auto& [field, count, part] :
         {std::tuple{"vertices", 0x7fffe00fu, "vertices cannot be held"},
          std::tuple{"triangles", 0x7fffe00fu, "triangles cannot be held"},
          std::tuple{"points", 0x7fffe00fu, "points cannot be held"}}) {
        SCOPED_TRACE(field);
        ChunkHeader h = readChunkHeader(message);
        if (std::string(field) == "vertices") h.vertexCount = count;
        if (std::string(field) == "triangles") h.triangleCount = count;
        if (std::string(field) == "points") h.pointCount = count;
        std::vector<uint8_t> lie = message;
        writeChunkHeader(h, lie.data());
        try {
            decodeChunk(lie);
            ADD_FAILURE() << "decoded";
        } catch (const ProtocolError& e) {
            EXPECT_NE(std::string(e.what()).find(part), std::string::npos) << e.what();
        }
    }
}

// ---------------------------------------------------------------------------------------------
// Messages

ViewMessage validView() {
    ViewMessage v;
    v.seq = 1;
    v.width = v.height = 256;
    v.eye = {0, -100, 0};
    v.target = {0, 0, 0};
    v.up = {0, 0, 1};
    v.fovYDegrees = 30;
    v.iso = 600.5;
    return v;
}

std::string viewError(const ViewMessage& v) {
    try {
        parseView(encodeView(v));
        return "";
    } catch (const ProtocolError& e) {
        return e.what();
    }
}

TEST(ServeProtocol, ViewRoundTrips) {
    const ViewMessage v = validView();
    const ViewMessage back = parseView(encodeView(v));
    EXPECT_EQ(back.seq, v.seq);
    EXPECT_EQ(back.width, v.width);
    EXPECT_EQ(back.eye, v.eye);
    EXPECT_EQ(back.up, v.up);
    EXPECT_EQ(back.iso, v.iso);
    EXPECT_EQ(encodeView(v).size(), kViewMessageBytes);
}

TEST(ServeProtocol, RefusesBadViews) {
    ViewMessage v = validView();
    v.eye.x = NAN;
    EXPECT_NE(viewError(v).find("finite"), std::string::npos);
    v = validView();
    v.target.z = INFINITY;
    EXPECT_NE(viewError(v).find("finite"), std::string::npos);
    v = validView();
    v.target = v.eye;
    EXPECT_NE(viewError(v).find("eye and target"), std::string::npos);
    v = validView();
    v.width = 8193;
    EXPECT_NE(viewError(v).find("viewport"), std::string::npos);
    v = validView();
    v.height = 0;
    EXPECT_NE(viewError(v).find("viewport"), std::string::npos);
    v = validView();
    v.up = {0, 1, 0};  // along the view
    EXPECT_NE(viewError(v).find("parallel"), std::string::npos);
    v = validView();
    v.fovYDegrees = 180;
    EXPECT_NE(viewError(v).find("fov"), std::string::npos);
    v = validView();
    v.iso = NAN;
    EXPECT_NE(viewError(v).find("iso"), std::string::npos);
    v = validView();
    v.seq = UINT32_MAX;  // the outbox's mark of control messages
    EXPECT_NE(viewError(v).find("seq"), std::string::npos);
    v = validView();
    v.iso = -0.0;
    EXPECT_FALSE(std::signbit(parseView(encodeView(v)).iso));  // one key for 0 and -0

    std::vector<uint8_t> bytes = encodeView(validView());
    bytes.pop_back();
    EXPECT_THROW(parseView(bytes), ProtocolError);
    bytes = encodeView(validView());
    bytes[1] = 2;  // version
    EXPECT_THROW(parseView(bytes), ProtocolError);
    bytes = encodeView(validView());
    bytes[0] = 99;
    EXPECT_THROW(clientMessageType(bytes), ProtocolError);
    EXPECT_THROW(clientMessageType(std::vector<uint8_t>{1, 1}), ProtocolError);
}

TEST(ServeProtocol, EvictSizesAreChecked) {
    EvictMessage e;
    e.seq = 3;
    e.iso = 2.5;
    e.bricks = {1, 5, 9};
    const EvictMessage back = parseEvict(encodeEvict(e));
    EXPECT_EQ(back.bricks, e.bricks);
    EXPECT_EQ(back.iso, e.iso);
    std::vector<uint8_t> bytes = encodeEvict(e);
    bytes.resize(bytes.size() - 4);  // count says 3, holds 2
    EXPECT_THROW(parseEvict(bytes), ProtocolError);
    bytes = encodeEvict(e);
    bytes[12] = 0xff, bytes[13] = 0xff, bytes[14] = 0xff;  // a huge count
    EXPECT_THROW(parseEvict(bytes), ProtocolError);
}

// ---------------------------------------------------------------------------------------------
// Chunks

TEST(ServeChunkCodec, RoundTripsWithinQuantization) {
    auto source = test::synthBrickSource({SynthKind::Head, {40, 40, 40}, ScalarType::U16, 1}, 16);
    TriangleMesh mesh;
    extractOctree(*source, {kHeadSkinIso, 4}, mesh);
    ASSERT_GT(mesh.triangleCount(), 100u);
    PointSet points;
    points.positions = {{1, 2, 3}, {4, 5, 6}};
    points.normals = {{0, 0, 1}, {0, -1, 0}};
    ChunkHeader h;
    h.flags = kChunkCacheable;
    h.frame = 7;
    h.brick = 11;
    h.iso = kHeadSkinIso;
    const std::vector<uint8_t> message = encodeChunk(h, mesh, points);
    const DecodedChunk d = decodeChunk(message);
    EXPECT_EQ(d.header.brick, 11u);
    EXPECT_EQ(d.header.frame, 7u);
    ASSERT_EQ(d.mesh.triangleCount(), mesh.triangleCount());
    ASSERT_EQ(d.points.size(), 2u);
    // The same triangles (in another order) at the positions the wire's 16 bits give.
    TriangleMesh expected = mesh;
    const glm::vec3 lo = d.header.boxMin, extent = d.header.boxMax - d.header.boxMin;
    for (glm::vec3& p : expected.positions)
        for (int k = 0; k < 3; ++k) {
            const float q = float(std::lround((p[k] - lo[k]) * (65535.0f / extent[k])));
            EXPECT_LE(std::abs(q / 65535.0f * extent[k] + lo[k] - p[k]), extent[k] / 65535.0f);
            p[k] = lo[k] + q / 65535.0f * extent[k];
        }
    EXPECT_EQ(test::canonicalTriangles(d.mesh), test::canonicalTriangles(expected));
    float worstNormal = 0;
    for (int i = 0; i < 2000; ++i) {  // the octahedral code on directions all round
        const float t = float(i) * 0.1f;
        const glm::vec3 n = glm::normalize(glm::vec3(std::cos(t) * std::sin(t * 0.37f),
                                                     std::sin(t) * std::sin(t * 0.37f), std::cos(t * 0.37f)));
        int8_t u, v;
        encodeOctahedral(n, u, v);
        worstNormal = std::max(worstNormal, glm::length(decodeOctahedral(u, v) - n));
    }
    EXPECT_LT(worstNormal, 0.02f);  // about a degree
    EXPECT_THROW(decodeChunk(std::span<const uint8_t>(message.data(), message.size() - 1)), ProtocolError);
}

TEST(ServeChunkCodec, EmptyPartsEncode) {
    // Found by fuzz_protocol (UBSan): a chunk of points only copied its empty vertex data from a
    // null buffer.
    PointSet points;
    points.positions = {{1, 2, 3}};
    points.normals = {{0, 0, 1}};
    const DecodedChunk onlyPoints = decodeChunk(encodeChunk(ChunkHeader{}, TriangleMesh{}, points));
    EXPECT_EQ(onlyPoints.points.size(), 1u);
    EXPECT_EQ(onlyPoints.mesh.triangleCount(), 0u);
    const DecodedChunk nothing = decodeChunk(encodeChunk(ChunkHeader{}, TriangleMesh{}, PointSet{}));
    EXPECT_EQ(nothing.points.size() + nothing.mesh.positions.size(), 0u);
}

// ---------------------------------------------------------------------------------------------
// The outbox

OutMessage frameMessage(uint32_t frame, size_t bytes) {
    OutMessage m;
    m.bytes = std::make_shared<const std::vector<uint8_t>>(bytes, uint8_t(1));
    m.frame = frame;
    return m;
}

TEST(ServeOutbox, NewerFrameDropsOlderAndReleasesBlockedPush) {
    Outbox box(1000, [] {});
    box.beginFrame(1);
    ASSERT_TRUE(box.push(frameMessage(1, 800)));
    ASSERT_TRUE(box.push(frameMessage(1, 800)));  // over the limit now: the next push waits
    std::future<bool> blocked = std::async(std::launch::async, [&] { return box.push(frameMessage(1, 800)); });
    EXPECT_EQ(blocked.wait_for(std::chrono::milliseconds(100)), std::future_status::timeout);
    box.push(OutMessage::control("{}"));  // control messages never wait
    box.beginFrame(2);                      // frame 1 superseded: dropped, the push released
    EXPECT_FALSE(blocked.get());
    const std::optional<OutMessage> m = box.pop();
    ASSERT_TRUE(m);
    EXPECT_TRUE(m->text);  // only the control message survived
    EXPECT_FALSE(box.pop());
    EXPECT_EQ(box.queuedBytes(), 0u);
    box.close();
    EXPECT_FALSE(box.push(frameMessage(2, 10)));
}

TEST(ServeOutbox, AFrameEndSaysSupersededWhenItsMessagesWereDropped) {
    Outbox box(1 << 20, [] {});
    box.beginFrame(1);
    ASSERT_TRUE(box.push(frameMessage(1, 100)));
    OutMessage end = OutMessage::control("complete");
    end.ends = 1;
    end.ifIncomplete = OutMessage::control("superseded").bytes;
    ASSERT_TRUE(box.push(end));
    box.beginFrame(2);  // frame 1's chunk had not been written: dropped
    const std::optional<OutMessage> m = box.pop();
    ASSERT_TRUE(m);
    EXPECT_EQ(std::string(m->bytes->begin(), m->bytes->end()), "superseded");

    // A frame whose messages all went out ends complete.
    box.beginFrame(3);
    ASSERT_TRUE(box.push(frameMessage(3, 100)));
    end.ends = 3;
    ASSERT_TRUE(box.push(end));
    EXPECT_TRUE(box.pop());
    box.beginFrame(4);
    const std::optional<OutMessage> e = box.pop();
    ASSERT_TRUE(e);
    EXPECT_EQ(std::string(e->bytes->begin(), e->bytes->end()), "complete");
}

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
    expectError(encodeView(v), false, "viewport");
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
    const Camera behind = presetFor(local, ViewPreset::Closeup, 128, 180);
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

    // Every GET answered 500: the frame behind the head needs bricks not yet fetched.
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
