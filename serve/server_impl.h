// Inside vdiso serve (serve/server.cpp, serve/connections.cpp): the server's state, shared by
// its accept loop and its connections. Not for use outside serve/.
#pragma once

#include <algorithm>
#include <atomic>
#include <list>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include <boost/asio/ip/tcp.hpp>
#include <boost/asio/signal_set.hpp>
#include <boost/asio/steady_timer.hpp>
#include <boost/beast/core.hpp>
#include <boost/beast/http.hpp>

#include "serve/frame_pool.h"
#include "serve/serve_settings.h"
#include "serve/session_directory.h"
#include "serve/server.h"
#include "serve/store_catalog.h"
#include "serve/viewer_session.h"
#include "serve/web_files.h"

namespace vdiso::serve {

namespace beast = boost::beast;
namespace http = beast::http;
namespace net = boost::asio;
using tcp = net::ip::tcp;

// One WebSocket connection (serve/connections.cpp).
class WsSession;
// Its viewer's work stops now (at its next brick); join() waits for its worker.
void stopSession(WsSession& session);
void joinSession(WsSession& session);

struct Server::Impl {
    ServeOptions options;
    // Set when the server stops: the stores' remote reads in flight end at once (RemoteOptions::stop).
    std::shared_ptr<std::atomic<bool>> stopReads = std::make_shared<std::atomic<bool>>(false);
    StoreCatalog stores;
    WebFiles web;
    SessionSettings settings;
    FramePool pool;  // every viewer's frames
    SessionDirectory directory;  // the viewers by session id, and who follows whom
    std::string token;
    uint16_t port = 0;
    std::mutex mutex;
    std::list<std::weak_ptr<WsSession>> sessions;
    // Sessions whose connection is gone, their workers stopping: joined off the I/O thread
    // (when the next connection comes, and at the end of run()), not where the socket closed.
    std::vector<std::unique_ptr<ViewerSession>> retired;
    std::atomic<uint64_t> sessionsOpened{0}, httpRequests{0}, httpRefused{0};
    std::atomic<uint64_t> acceptsBackedOff{0}, viewersRefused{0}, viewersDropped{0};
    std::chrono::milliseconds acceptPause{0};  // the back-off after a failed accept (I/O thread only)
    std::atomic<bool> stopping{false};
    // Last, so destroyed first: its pending handlers hold connections, whose destructors
    // retire sessions into the members above.
    net::io_context ioc{1};
    tcp::acceptor acceptor{ioc};
    net::signal_set signals{ioc};
    net::steady_timer acceptTimer{ioc};

    explicit Impl(const ServeOptions& o)
        : options(withDefaults((checkServeOptions(o), o))),
          stores(o.stores, o.cacheBytes, o.chunkCacheBytes, o.iso, withStop(o.remote, stopReads), o.threads), web(o.webRoot),
          settings(sessionSettings(o, stores)), pool(frameSlots(stores, settings)),
          token(o.token.empty() ? randomToken() : o.token) {}

    static RemoteOptions withStop(RemoteOptions remote, std::shared_ptr<std::atomic<bool>> stop) {
        remote.stop = std::move(stop);
        return remote;
    }
    void accept();
    void shutdown();
    size_t openSessions() {
        std::lock_guard lock(mutex);
        return size_t(std::count_if(sessions.begin(), sessions.end(),
                                    [](const std::weak_ptr<WsSession>& w) { return !w.expired(); }));
    }
    void retire(std::unique_ptr<ViewerSession> session);
    void joinRetired(bool all);
    std::string cookieName() const { return "vdiso_token_" + std::to_string(port); }
    bool authorized(const http::request<http::string_body>& request, bool& fromQuery) const;
};

// Serves one accepted connection: the viewer's files, or the upgrade to a WebSocket.
void startHttpConnection(tcp::socket&& socket, Server::Impl& server);

}  // namespace vdiso::serve
