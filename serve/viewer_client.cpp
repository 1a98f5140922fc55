#include "serve/viewer_client.h"

#include <boost/asio/connect.hpp>
#include <boost/asio/ip/tcp.hpp>
#include <boost/beast/core.hpp>
#include <boost/beast/websocket.hpp>
#include <nlohmann/json.hpp>

#include "core/clock.h"
#include "io/error.h"

namespace vdiso::serve {

namespace beast = boost::beast;
namespace websocket = beast::websocket;
namespace net = boost::asio;
using tcp = net::ip::tcp;

struct ViewerClient::Connection {
    net::io_context ioc;
    websocket::stream<tcp::socket> ws{ioc};
};

namespace {

std::string typeOf(const std::string& text) {
    const nlohmann::json j = nlohmann::json::parse(text, nullptr, false);
    if (j.is_discarded() || !j.is_object() || !j.contains("type") || !j["type"].is_string())
        throw ProtocolError("server sent text that is not a typed JSON object: " + text.substr(0, 200));
    return j["type"].get<std::string>();
}

}  // namespace

ViewerClient::ViewerClient(const std::string& host, uint16_t port, const std::string& token, const std::string& query)
    : mConnection(std::make_unique<Connection>()) {
    try {
        tcp::resolver resolver(mConnection->ioc);
        net::connect(mConnection->ws.next_layer(), resolver.resolve(host, std::to_string(port)));
        mConnection->ws.next_layer().set_option(tcp::no_delay(true));
        mConnection->ws.read_message_max(uint64_t(1) << 30);
        mConnection->ws.handshake(host + ":" + std::to_string(port), "/ws?token=" + token + (query.empty() ? "" : "&" + query));
    } catch (const beast::system_error& e) {
        throw IoError(host + ":" + std::to_string(port) + ": WebSocket connection failed: " + e.code().message());
    }
    mHello = readText();
    if (typeOf(mHello) != "hello") throw ProtocolError("the server's first message is not hello: " + mHello);
}

ViewerClient::~ViewerClient() { close(); }

void ViewerClient::close() {
    if (!mConnection || !mConnection->ws.is_open()) return;
    beast::error_code ignored;
    mConnection->ws.close(websocket::close_code::normal, ignored);
}

void ViewerClient::interrupt() {
    beast::error_code ignored;
    mConnection->ws.next_layer().shutdown(tcp::socket::shutdown_both, ignored);
}

bool ViewerClient::read(std::vector<uint8_t>& message) {
    beast::flat_buffer buffer;
    try {
        mConnection->ws.read(buffer);
    } catch (const beast::system_error& e) {
        throw IoError("WebSocket read failed: " + e.code().message());
    }
    const auto data = buffer.cdata();
    const auto* bytes = static_cast<const uint8_t*>(data.data());
    message.assign(bytes, bytes + data.size());
    return mConnection->ws.got_text();
}

void ViewerClient::sendRaw(const std::vector<uint8_t>& bytes, bool text) {
    mConnection->ws.text(text);
    mConnection->ws.write(net::buffer(bytes));
}

std::string ViewerClient::readText() {
    std::vector<uint8_t> message;
    while (!read(message))
        if (!message.empty() && message[0] == uint8_t(MessageType::Chunk)) keep(decodeOrNot(message), message.size());
    return std::string(message.begin(), message.end());
}

DecodedChunk ViewerClient::decodeOrNot(const std::vector<uint8_t>& message) const {
    if (mDecode) return decodeChunk(message);
    DecodedChunk header;
    header.header = readChunkHeader(message);
    return header;
}

void ViewerClient::keep(DecodedChunk chunk, size_t bytes) {
    const auto key = std::make_tuple(chunk.header.store, chunk.header.iso, chunk.header.brick);
    mCacheBytes[key] = bytes;
    mCache[key] = std::move(chunk);
}

void ViewerClient::sendView(const ViewMessage& view) {
    mSent = Clock::now();
    mViews[view.seq] = {view.store, view.iso};
    sendRaw(encodeView(view));
}

ClientFrame ViewerClient::requestFrame(const ViewMessage& view) {
    sendView(view);
    return readFrame(view.seq);
}

ClientFrame ViewerClient::readFrame(uint32_t frame) {
    const auto view = mViews.find(frame);
    if (view == mViews.end()) throw ProtocolError("no VIEW was sent for frame " + std::to_string(frame));
    ClientFrame f;
    f.frame = frame;
    f.store = view->second.first;
    f.iso = view->second.second;
    return readUntilEnd(std::move(f), false);
}

ClientFrame ViewerClient::readFollowedFrame() { return readUntilEnd(ClientFrame{}, true); }

std::string ViewerClient::session() const { return nlohmann::json::parse(mHello).value("session", std::string()); }

ClientFrame ViewerClient::readUntilEnd(ClientFrame f, bool followed) {
    uint32_t frame = f.frame;
    bool begun = !followed;
    std::vector<uint8_t> message;
    auto since = [&] { return std::chrono::duration<double>(Clock::now() - mSent).count(); };
    while (true) {
        if (read(message)) {
            const std::string text(message.begin(), message.end());
            const std::string type = typeOf(text);
            if (type == "error") f.errors.push_back(text);
            if (type == "frameBegin") {
                ++f.framesBegun;
                const nlohmann::json j = nlohmann::json::parse(text);
                // A follower's frame is the one that begins (a newer one replaces it).
                if (followed && (!begun || j.value("frame", int64_t(-1)) != int64_t(frame))) {
                    const int begins = f.framesBegun;
                    std::vector<std::string> errors = std::move(f.errors);
                    f = ClientFrame{};
                    f.framesBegun = begins;
                    f.errors = std::move(errors);
                    frame = f.frame = uint32_t(j.value("frame", int64_t(0)));
                    f.store = uint32_t(j.value("store", int64_t(0)));
                    f.iso = j.value("iso", 0.0);
                    begun = true;
                }
            }
            if (type != "frameEnd" || !begun) continue;
            const nlohmann::json j = nlohmann::json::parse(text);
            if (j.value("frame", int64_t(-1)) != int64_t(frame)) continue;
            f.status = j.value("status", std::string());
            if (!j.value("final", true) && f.status == "complete") {
                // A coarse frame of this VIEW, complete: the final one follows and stands alone.
                if (f.coarseFrames++ == 0) {
                    f.coarseCompleteSeconds = since();
                    f.coarseTriangles = j.value("triangles", uint64_t(0));
                }
                f.chunks.clear();
                f.refs.clear();
                f.transient.clear();
                f.binaryBytes = 0;
                f.missingRefs = 0;
                continue;
            }
            f.frameEnd = text;
            f.completeSeconds = since();
            return f;
        }
        if (message.empty()) throw ProtocolError("empty binary message");
        if (message[0] == uint8_t(MessageType::Chunk)) {
            DecodedChunk chunk = decodeOrNot(message);
            const bool cacheable = chunk.header.flags & kChunkCacheable;
            const bool ours = begun && chunk.header.frame == frame;
            if (ours && f.firstGeometrySeconds < 0) f.firstGeometrySeconds = since();
            if (ours) f.binaryBytes += message.size();
            if (ours && cacheable) f.chunks.push_back(chunk.header.brick);
            // An older frame's cacheable chunk is held all the same: the server counts it so.
            if (cacheable)
                keep(std::move(chunk), message.size());
            else if (ours)
                f.transient.push_back(std::move(chunk));
        } else if (message[0] == uint8_t(MessageType::Refs)) {
            uint32_t refsFrame = 0;
            const std::vector<uint32_t> bricks = decodeRefs(message, refsFrame);
            if (!begun || refsFrame != frame) continue;
            if (f.firstGeometrySeconds < 0) f.firstGeometrySeconds = since();
            f.binaryBytes += message.size();
            f.refs.insert(f.refs.end(), bricks.begin(), bricks.end());
            for (const uint32_t b : bricks) f.missingRefs += !mCache.contains({f.store, f.iso, b});
        } else {
            throw ProtocolError("unknown binary message type " + std::to_string(message[0]));
        }
    }
}

void ViewerClient::evict(uint32_t store, double iso, const std::vector<uint32_t>& bricks) {
    EvictMessage e;
    e.seq = ++mEvictSeq;
    e.store = store;
    e.iso = iso;
    e.bricks = bricks;
    for (const uint32_t b : bricks) {
        mCache.erase({store, iso, b});
        mCacheBytes.erase({store, iso, b});
    }
    sendRaw(encodeEvict(e));
    while (true) {
        const std::string text = readText();
        if (typeOf(text) != "evicted") continue;
        if (nlohmann::json::parse(text).value("seq", int64_t(-1)) == int64_t(e.seq)) return;
    }
}

uint64_t ViewerClient::chunkBytes(uint32_t store, double iso, uint32_t brick) const {
    const auto it = mCacheBytes.find({store, iso, brick});
    return it == mCacheBytes.end() ? 0 : it->second;
}

void ViewerClient::assemble(const ClientFrame& frame, TriangleMesh& mesh, PointSet& points) const {
    auto add = [&](const DecodedChunk& c) {
        const uint32_t offset = uint32_t(mesh.positions.size());
        mesh.positions.insert(mesh.positions.end(), c.mesh.positions.begin(), c.mesh.positions.end());
        mesh.normals.insert(mesh.normals.end(), c.mesh.normals.begin(), c.mesh.normals.end());
        for (const uint32_t v : c.mesh.indices) mesh.indices.push_back(v + offset);
        points.positions.insert(points.positions.end(), c.points.positions.begin(), c.points.positions.end());
        points.normals.insert(points.normals.end(), c.points.normals.begin(), c.points.normals.end());
    };
    for (const std::vector<uint32_t>* list : {&frame.chunks, &frame.refs})
        for (const uint32_t brick : *list) {
            const auto it = mCache.find({frame.store, frame.iso, brick});
            if (it != mCache.end()) add(it->second);
        }
    for (const DecodedChunk& c : frame.transient) add(c);
}

}  // namespace vdiso::serve
