// vdiso serve's messages on their own, without a server: the protocol's client messages and
// their validation, the chunk codec (round trips, quantization, hostile counts), and the
// outbox (a newer frame dropping an older one's messages, a frame end saying so).
#include <gtest/gtest.h>

#include <cmath>
#include <future>
#include <string>
#include <thread>
#include <vector>

#include "core/extract/extract_full.h"
#include "core/synth/synth.h"
#include "serve/chunk_codec.h"
#include "serve/outbox.h"
#include "serve/protocol.h"
#include "serve/session_directory.h"
#include "tests/extract_test_util.h"
#include "tests/test_util.h"

namespace vdiso {
namespace {

using namespace serve;

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
    EXPECT_NE(viewError(v).find("width and height"), std::string::npos);
    v = validView();
    v.height = 0;
    EXPECT_NE(viewError(v).find("width and height"), std::string::npos);
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

}  // namespace
}  // namespace vdiso

namespace vdiso::serve {
namespace {

struct NoSession final : FollowedSession {
    void catchUp(std::shared_ptr<ViewerOutput>, const ViewMessage&) override {}
    void stopLeading() override {}
};

// A message read after its viewer closed (bytes the socket still held when a write failed) is
// refused as a protocol error, which the session answers; it used to throw std::out_of_range
// from the directory on the I/O thread and end the server.
TEST(ServeDirectory, AMessageOfAClosedSessionIsAProtocolError) {
    SessionDirectory directory;
    NoSession session;
    const std::string id = directory.add(session, std::make_shared<ViewerOutput>(size_t(1) << 20, [] {}));
    ViewMessage view;
    view.seq = 1;
    directory.acceptView(id, view);
    directory.remove(id);
    view.seq = 2;
    EXPECT_THROW(directory.acceptView(id, view), ProtocolError);
    EXPECT_THROW(directory.handOver(id, ""), ProtocolError);
    EXPECT_TRUE(directory.outputsOf(id).empty());
}

}  // namespace
}  // namespace vdiso::serve
