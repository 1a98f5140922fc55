// vdiso serve's connections: HTTP (the viewer's files, the upgrade) and WebSocket (a viewer's
// messages in, its queued frames out, with the write timeout).
#include <fstream>
#include <sstream>

#include <boost/asio/dispatch.hpp>
#include <boost/asio/post.hpp>
#include <boost/asio/strand.hpp>
#include <boost/beast/websocket.hpp>

#include "io/error.h"
#include "io/json.h"
#include "serve/server_impl.h"

// The WebSocket's stream reads first what came with the upgrade request
// (beast::buffered_read_stream); closing it closes the TCP stream below, which Beast knows how
// to tear down.
namespace boost::beast {
template <class TeardownHandler>
void async_teardown(role_type role, buffered_read_stream<tcp_stream, flat_buffer>& stream, TeardownHandler&& handler) {
    async_teardown(role, stream.next_layer(), std::forward<TeardownHandler>(handler));
}
inline void teardown(role_type role, buffered_read_stream<tcp_stream, flat_buffer>& stream, error_code& error) {
    teardown(role, stream.next_layer(), error);
}
}  // namespace boost::beast

namespace vdiso::serve {

namespace websocket = beast::websocket;

namespace {

constexpr const char* kServerName = "vdiso";
constexpr auto kHttpTimeout = std::chrono::seconds(30);
constexpr size_t kReadPiece = 64 * 1024;  // WebSocket reads in pieces, so size is checked as it comes
constexpr int kSendBuffer = 512 * 1024;    // SO_SNDBUF (Linux doubles it): 1 MB in the kernel a viewer

}  // namespace

// One WebSocket connection: reads messages into the session, writes what it queues.
class WsSession : public std::enable_shared_from_this<WsSession> {
public:
    // `early`: bytes the client sent after its upgrade request, read with it (a VIEW pipelined
    // behind the handshake): the WebSocket reads them first.
    WsSession(tcp::socket&& socket, beast::flat_buffer&& early, Server::Impl& server)
        : mWs(std::move(socket)), mServer(server) {
        auto& buffered = mWs.next_layer().buffer();
        buffered.commit(net::buffer_copy(buffered.prepare(early.size()), early.data()));
    }

    ~WsSession() {
        if (mViewer) mServer.retire(std::move(mViewer));
    }

    void run(http::request<http::string_body> request) {
        // Small messages (REFS, frame ends) go at once: Nagle's algorithm would hold them for
        // the client's delayed ACK, 40 ms on Linux.
        beast::error_code ignored;
        beast::get_lowest_layer(mWs).socket().set_option(tcp::no_delay(true), ignored);
        // The kernel's share of a client's queue is bounded (Linux grows a send buffer to 4 MB
        // on its own): a client that stops reading blocks a write within kSendBuffer bytes,
        // and from there the write timeout counts.
        beast::get_lowest_layer(mWs).socket().set_option(net::socket_base::send_buffer_size(kSendBuffer), ignored);
        mWs.set_option(websocket::stream_base::timeout::suggested(beast::role_type::server));
        mWs.set_option(websocket::stream_base::decorator(
            [](websocket::response_type& r) { r.set(http::field::server, kServerName); }));
        mWs.read_message_max(0);  // sizes are checked as pieces arrive (readPiece)
        // Holds no executor: the session may be retired (serve/server.cpp, retire) and outlive
        // the I/O context, and an executor must not.
        std::weak_ptr<WsSession> weak = weak_from_this();
        mViewer = std::make_unique<ViewerSession>(mServer.stores, mServer.settings, mServer.pool, mServer.directory, [weak] {
            if (auto self = weak.lock()) net::post(self->mWs.get_executor(), [self] { self->pump(); });
        });
        // ?follow=ID: this viewer sees session ID's frames (docs/protocol.md, "Follow mode").
        const std::string target(request.target());
        const size_t q = target.find('?');
        if (q != std::string::npos) mFollow = findParameter(target.substr(q + 1), "follow", '&').value_or("");
        mWs.async_accept(request, beast::bind_front_handler(&WsSession::onAccept, shared_from_this()));
    }

    // The server is stopping: the session's work stops now (at its next brick) and its
    // worker is joined; the socket closes with the I/O context.
    void stop() {
        if (mViewer) close();
    }
    void join() {
        if (mViewer) mViewer->join();
    }

private:
    void onAccept(beast::error_code error) {
        if (error) return;
        try {
            mViewer->start(mFollow);
        } catch (const std::exception& e) {
            // No memory for this viewer: it is told and closed; the others and the server go on.
            ++mServer.viewersRefused;
            refuse("the server cannot take another viewer now (" + std::string(e.what()) + "); try again later");
            return;
        }
        ++mServer.sessionsOpened;
        readPiece();
    }

    // Sends one error message and closes the WebSocket (policy error), on this connection's strand.
    void refuse(const std::string& message) {
        JsonObject o;
        o.add("type", "error").add("message", message);
        auto text = std::make_shared<std::string>(o.str());
        mWs.text(true);
        mWs.async_write(net::buffer(*text), [self = shared_from_this(), text](beast::error_code e, size_t) {
            if (e) return;
            self->mWs.async_close(websocket::close_code::policy_error, [self](beast::error_code) {});
        });
    }

    void readPiece() {
        mWs.async_read_some(mBuffer, kReadPiece,
                            beast::bind_front_handler(&WsSession::onRead, shared_from_this()));
    }

    void onRead(beast::error_code error, size_t bytes) {
        // Closed by the client, or broken: its work stops now. A read that completes after a
        // write failed (bytes the socket held) is dropped: the viewer is closed already.
        if (error || mClosed) {
            close();
            return;
        }
        mMessageBytes += bytes;
        if (mMessageBytes > kMaxClientMessageBytes) mBuffer.consume(mBuffer.size());  // skipped
        if (mWs.is_message_done()) {
            if (mMessageBytes > kMaxClientMessageBytes) {
                mViewer->onOversize(mMessageBytes);
            } else {
                const auto data = mBuffer.cdata();
                mViewer->onMessage({static_cast<const uint8_t*>(data.data()), data.size()}, mWs.got_text());
            }
            mBuffer.consume(mBuffer.size());
            mMessageBytes = 0;
        }
        // A client that sends but does not read gets no more replies queued than the limit:
        // its messages wait in the socket until the outbox drains.
        if (mViewer->backlogged())
            mReadPaused = true;
        else
            readPiece();
    }

    // The viewer's work stops and nothing more is read or written for it (on this strand).
    void close() {
        mClosed = true;
        mViewer->close();
    }

    // Writes the next queued message unless one is being written.
    void pump() {
        if (mWriting || mClosed) return;
        mCurrent = mViewer->nextToWrite();
        if (!mCurrent) return;
        mWriting = true;
        mWs.text(mCurrent->text);
        mWs.async_write(net::buffer(*mCurrent->bytes),
                        beast::bind_front_handler(&WsSession::onWrite, shared_from_this()));
        // A client that stopped reading leaves the write pending: after the timeout the
        // connection is closed, which ends the write with an error and the session with it.
        mWriteTimer.expires_after(std::chrono::milliseconds(int64_t(mServer.options.writeTimeoutSeconds * 1000)));
        mWriteTimer.async_wait([self = shared_from_this()](beast::error_code e) {
            if (e || !self->mWriting) return;
            ++self->mServer.viewersDropped;
            beast::error_code ignored;
            beast::get_lowest_layer(self->mWs).socket().shutdown(tcp::socket::shutdown_both, ignored);
            beast::get_lowest_layer(self->mWs).close();
        });
    }

    void onWrite(beast::error_code error, size_t) {
        mWriting = false;
        mWriteTimer.cancel();
        mCurrent.reset();
        if (error || mClosed) {
            close();
            return;
        }
        if (mReadPaused && !mViewer->backlogged()) {
            mReadPaused = false;
            readPiece();
        }
        pump();
    }

    websocket::stream<beast::buffered_read_stream<beast::tcp_stream, beast::flat_buffer>> mWs;
    Server::Impl& mServer;
    beast::flat_buffer mBuffer;
    uint64_t mMessageBytes = 0;
    std::unique_ptr<ViewerSession> mViewer;
    std::string mFollow;  // the session this viewer asked to follow
    std::optional<OutMessage> mCurrent;
    bool mWriting = false;
    bool mReadPaused = false;
    bool mClosed = false;  // the viewer closed: a late read or write completion does nothing
    net::steady_timer mWriteTimer{mWs.get_executor()};
};

void stopSession(WsSession& session) { session.stop(); }
void joinSession(WsSession& session) { session.join(); }

namespace {

// One HTTP connection: the viewer's files, or the upgrade to a WebSocket.
class HttpSession : public std::enable_shared_from_this<HttpSession> {
public:
    HttpSession(tcp::socket&& socket, Server::Impl& server) : mStream(std::move(socket)), mServer(server) {}

    void run() {
        net::dispatch(mStream.get_executor(), beast::bind_front_handler(&HttpSession::read, shared_from_this()));
    }

private:
    void read() {
        mParser.emplace();
        mParser->header_limit(16 * 1024);
        mParser->body_limit(16 * 1024);
        mStream.expires_after(kHttpTimeout);
        http::async_read(mStream, mBuffer, *mParser,
                         beast::bind_front_handler(&HttpSession::onRead, shared_from_this()));
    }

    void onRead(beast::error_code error, size_t) {
        if (error == http::error::end_of_stream) {
            mStream.socket().shutdown(tcp::socket::shutdown_send, error);
            return;
        }
        if (error) {  // malformed, too large or timed out: answer once, then close
            if (error != beast::error::timeout && error != net::error::operation_aborted)
                send(reply(http::status::bad_request, "malformed request: " + error.message() + "\n", 11, false));
            return;
        }
        http::request<http::string_body> request = mParser->release();
        ++mServer.httpRequests;
        bool fromQuery = false;
        const bool allowed = mServer.authorized(request, fromQuery);
        if (websocket::is_upgrade(request)) {
            const std::string target(request.target());
            // A browser says which page opens a socket: only this server's own page may. The
            // token is what protects the server (a rebound host name controls Host and Origin
            // alike); this keeps other sites' pages off it even where a token has leaked.
            const auto origin = request.find(http::field::origin);
            const auto host = request.find(http::field::host);
            const bool sameOrigin = origin == request.end() ||
                                    (host != request.end() && origin->value() == "http://" + std::string(host->value()));
            const bool full = mServer.openSessions() >= size_t(mServer.options.maxViewers);
            if (allowed && sameOrigin && target.substr(0, target.find('?')) == "/ws" && !mServer.stopping && !full) {
                mStream.expires_never();
                auto session = std::make_shared<WsSession>(mStream.release_socket(), std::move(mBuffer), mServer);
                {
                    std::lock_guard lock(mServer.mutex);
                    std::erase_if(mServer.sessions, [](const std::weak_ptr<WsSession>& w) { return w.expired(); });
                    mServer.sessions.push_back(session);
                }
                session->run(std::move(request));
                return;
            }
            ++mServer.httpRefused;
            if (allowed && sameOrigin && full) {
                ++mServer.viewersRefused;
                send(reply(http::status::service_unavailable,
                           "the server has its most viewers (" + std::to_string(mServer.options.maxViewers) +
                               "); try again later\n",
                           request.version(), false));
                return;
            }
            send(reply(!allowed ? http::status::forbidden
                       : !sameOrigin ? http::status::forbidden
                                     : http::status::not_found,
                       !allowed ? "access token missing or wrong\n"
                       : !sameOrigin ? "WebSocket from another origin refused\n"
                                     : "no such WebSocket endpoint (use /ws)\n",
                       request.version(), false));
            return;
        }
        send(respond(request, allowed, fromQuery));
    }

    http::response<http::string_body> reply(http::status status, std::string body, unsigned version,
                                            bool keepAlive, const std::string& type = "text/plain; charset=utf-8") {
        http::response<http::string_body> r{status, version};
        r.set(http::field::server, kServerName);
        r.set(http::field::content_type, type);
        r.set(http::field::cache_control, "no-store");
        r.set("X-Content-Type-Options", "nosniff");
        r.keep_alive(keepAlive);
        r.body() = std::move(body);
        r.prepare_payload();
        return r;
    }

    http::response<http::string_body> respond(const http::request<http::string_body>& request,
                                              bool allowed, bool fromQuery) {
        const unsigned version = request.version();
        const bool keepAlive = request.keep_alive();
        if (!allowed) {
            ++mServer.httpRefused;
            return reply(http::status::forbidden,
                         "access token missing or wrong: open the URL vdiso serve printed\n", version, keepAlive);
        }
        if (request.method() != http::verb::get && request.method() != http::verb::head) {
            ++mServer.httpRefused;
            return reply(http::status::method_not_allowed, "only GET and HEAD\n", version, keepAlive);
        }
        const std::string target(request.target());
        const std::optional<WebFile> file = mServer.web.find(target.substr(0, target.find('?')));
        if (!file) {
            ++mServer.httpRefused;
            return reply(http::status::not_found, "not found\n", version, keepAlive);
        }
        std::ifstream in(file->path, std::ios::binary);
        std::ostringstream body;
        body << in.rdbuf();
        if (!in) return reply(http::status::internal_server_error, "cannot read the file\n", version, keepAlive);
        http::response<http::string_body> r = reply(http::status::ok, body.str(), version, keepAlive, file->contentType);
        // A page opened with the token in its URL gets it as a cookie, for its modules and socket.
        if (fromQuery)
            r.set(http::field::set_cookie,
                  mServer.cookieName() + "=" + mServer.token + "; HttpOnly; SameSite=Strict; Path=/");
        if (request.method() == http::verb::head) {
            r.body().clear();
            r.content_length(body.str().size());
        }
        return r;
    }

    void send(http::response<http::string_body>&& response) {
        auto r = std::make_shared<http::response<http::string_body>>(std::move(response));
        http::async_write(mStream, *r, [self = shared_from_this(), r](beast::error_code error, size_t) {
            if (error || !r->keep_alive()) {
                self->mStream.socket().shutdown(tcp::socket::shutdown_send, error);
                return;
            }
            self->read();
        });
    }

    beast::tcp_stream mStream;
    Server::Impl& mServer;
    beast::flat_buffer mBuffer;
    std::optional<http::request_parser<http::string_body>> mParser;
};

}  // namespace

void startHttpConnection(tcp::socket&& socket, Server::Impl& server) {
    std::make_shared<HttpSession>(std::move(socket), server)->run();
}

bool Server::Impl::authorized(const http::request<http::string_body>& request, bool& fromQuery) const {
    const std::string target(request.target());
    const size_t q = target.find('?');
    if (q != std::string::npos) {
        const std::optional<std::string> given = findParameter(target.substr(q + 1), "token", '&');
        if (given && constantTimeEquals(*given, token)) {
            fromQuery = true;
            return true;
        }
    }
    const auto cookie = request.find(http::field::cookie);
    if (cookie != request.end()) {
        // Named by the port: cookies are per host, not per port, and two servers may run.
        const std::optional<std::string> given = findParameter(std::string(cookie->value()), cookieName(), ';');
        if (given && constantTimeEquals(*given, token)) return true;
    }
    return false;
}

}  // namespace vdiso::serve
