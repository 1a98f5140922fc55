#include "serve/server.h"

#include <cstdio>

#include <boost/asio/post.hpp>
#include <boost/asio/strand.hpp>

#include "io/error.h"
#include "serve/server_impl.h"

namespace vdiso::serve {

// Out of descriptors or memory, an accept fails at once for as long as the shortage lasts:
// retrying at once would spin a core. The server waits (10 ms, doubling to 1 s while it lasts),
// says so once per shortage, and serves the viewers it has meanwhile.
static bool isShortage(const beast::error_code& error) {
    return error == net::error::no_descriptors || error == net::error::no_memory ||
           error == net::error::no_buffer_space || error.value() == ENFILE;
}

void Server::Impl::accept() {
    acceptor.async_accept(net::make_strand(ioc), [this](beast::error_code error, tcp::socket socket) {
        if (stopping || error == net::error::operation_aborted) return;
        if (isShortage(error)) {
            if (acceptPause.count() == 0)
                std::fprintf(stderr, "vdiso serve: cannot accept a connection (%s): waiting for one to close\n",
                             error.message().c_str());
            ++acceptsBackedOff;
            acceptPause = std::clamp(acceptPause * 2, std::chrono::milliseconds(10), std::chrono::milliseconds(1000));
            acceptTimer.expires_after(acceptPause);
            acceptTimer.async_wait([this](beast::error_code e) {
                if (!e && !stopping) accept();
            });
            return;
        }
        acceptPause = std::chrono::milliseconds(0);
        if (!error) {
            // A connection that cannot be set up (memory) is dropped; the server goes on.
            try {
                joinRetired(false);
                startHttpConnection(std::move(socket), *this);
            } catch (const std::exception&) {
            }
        }
        // Other errors (a connection reset before it was accepted) pass: the server keeps
        // accepting.
        accept();
    });
}

void Server::Impl::retire(std::unique_ptr<ViewerSession> session) {
    session->close();
    std::lock_guard lock(mutex);
    retired.push_back(std::move(session));
}

void Server::Impl::joinRetired(bool all) {
    std::vector<std::unique_ptr<ViewerSession>> done;
    {
        std::lock_guard lock(mutex);
        std::erase_if(retired, [&](std::unique_ptr<ViewerSession>& s) {
            if (!all && !s->stopped()) return false;
            done.push_back(std::move(s));
            return true;
        });
    }
    done.clear();  // joins (at once, unless `all`)
}

void Server::Impl::shutdown() {
    if (stopping.exchange(true)) return;
    *stopReads = true;  // remote reads in flight end now, and their frames with them
    beast::error_code ignored;
    acceptor.close(ignored);
    acceptTimer.cancel();
    signals.cancel(ignored);
    {
        std::lock_guard lock(mutex);
        for (const std::weak_ptr<WsSession>& w : sessions)
            if (auto s = w.lock()) stopSession(*s);
    }
    // Idle HTTP connections hold no work worth waiting for; sockets close with the context.
    ioc.stop();
}

Server::Server(const ServeOptions& options) : mImpl(std::make_unique<Impl>(options)) {
    Impl& s = *mImpl;
    beast::error_code error;
    const net::ip::address address = net::ip::make_address(options.host, error);
    if (error) throw IoError("the host " + options.host + " to listen on is not an IP address: " + error.message());
    const tcp::endpoint endpoint(address, options.port);
    s.acceptor.open(endpoint.protocol(), error);
    if (!error) s.acceptor.set_option(net::socket_base::reuse_address(true), error);
    if (!error) s.acceptor.bind(endpoint, error);
    if (!error) s.acceptor.listen(net::socket_base::max_listen_connections, error);
    if (error)
        throw IoError(options.host + ":" + std::to_string(options.port) + ": cannot listen: " + error.message());
    if (options.handleSignals) {
        s.signals.add(SIGINT);
        s.signals.add(SIGTERM);
        s.signals.async_wait([this](beast::error_code e, int) {
            if (!e) mImpl->shutdown();
        });
    }
    s.port = s.acceptor.local_endpoint(error).port();
    s.accept();
}

Server::~Server() {
    stop();
}

uint16_t Server::port() const { return mImpl->port; }

const std::string& Server::token() const { return mImpl->token; }

std::string Server::url() const {
    const std::string host = mImpl->options.host.find(':') != std::string::npos
                                 ? "[" + mImpl->options.host + "]"
                                 : mImpl->options.host;
    return "http://" + host + ":" + std::to_string(port()) + "/?token=" + mImpl->token;
}

void Server::run() {
    mImpl->ioc.run();
    // Every session's worker is stopped before the context (and the sockets) go away.
    std::list<std::weak_ptr<WsSession>> sessions;
    {
        std::lock_guard lock(mImpl->mutex);
        sessions = mImpl->sessions;
    }
    for (const std::weak_ptr<WsSession>& w : sessions)
        if (auto s = w.lock()) {
            stopSession(*s);
            joinSession(*s);
        }
    mImpl->joinRetired(true);
}

void Server::stop() {
    net::post(mImpl->ioc, [this] { mImpl->shutdown(); });
    if (mImpl->ioc.stopped()) mImpl->shutdown();
}

ServerCounters Server::counters() const {
    ServerCounters c;
    c.sessionsOpened = mImpl->sessionsOpened;
    {
        std::lock_guard lock(mImpl->mutex);
        for (const auto& w : mImpl->sessions) c.sessionsOpen += !w.expired();
    }
    c.httpRequests = mImpl->httpRequests;
    c.httpRefused = mImpl->httpRefused;
    c.acceptsBackedOff = mImpl->acceptsBackedOff;
    c.viewersRefused = mImpl->viewersRefused;
    c.viewersDropped = mImpl->viewersDropped;
    c.framePasses = mImpl->pool.passes();
    c.frameWorkers = uint64_t(mImpl->pool.workers());
    for (size_t i = 0; i < mImpl->stores.size(); ++i) {
        const SharedChunks::Counters shared = mImpl->stores[i].chunks->counters();
        c.chunksEncoded += shared.encoded;
        c.chunksShared += shared.reused;
    }
    return c;
}

}  // namespace vdiso::serve
