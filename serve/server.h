// `vdiso serve`: HTTP for the viewer's files and a WebSocket per browser that streams the
// visible surface as the camera moves (docs/design.md, "The server"; docs/protocol.md).
//
// One process holds the stores and one brick cache per store, shared by every frame of every
// client. Each WebSocket connection is a ViewerSession (serve/viewer_session.h); a fixed pool
// of workers (serve/frame_pool.h) runs every viewer's frames in turn, so the threads do not
// grow with the viewers; networking runs on one I/O thread (Boost.Beast), reads and writes of a
// connection on its strand. Every request needs the access token (in the URL or its cookie);
// only the viewer's files are served (serve/web_files.h). A malformed request or message is
// answered with an error; neither the connection nor the server goes down for it.
#pragma once

#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "serve/serve_options.h"

namespace vdiso::serve {

struct ServerCounters {
    uint64_t sessionsOpened = 0, sessionsOpen = 0;
    uint64_t httpRequests = 0, httpRefused = 0;
    // Accepts that failed for want of a resource (descriptors, memory): each backs off before
    // the next accept. Viewers refused because no memory could be had for them.
    uint64_t acceptsBackedOff = 0, viewersRefused = 0;
    uint64_t viewersDropped = 0;  // their writes timed out
    uint64_t framePasses = 0;     // extraction passes begun, all viewers (a VIEW's coarse and final)
    uint64_t frameWorkers = 0;    // the threads running them (serve/frame_pool.h), however many viewers
    // Cacheable chunks encoded, and sent from the shared chunks instead (every store).
    uint64_t chunksEncoded = 0, chunksShared = 0;
};

class Server {
public:
    // Checks the options, opens the stores and the viewer's files and binds the port. Throws
    // SettingsError for an option, IoError naming what fails (a store, the web folder, the address).
    explicit Server(const ServeOptions& options);
    ~Server();
    Server(const Server&) = delete;
    Server& operator=(const Server&) = delete;

    uint16_t port() const;
    const std::string& token() const;
    // http://HOST:PORT/?token=TOKEN
    std::string url() const;

    // Serves until stop() (or a signal, with handleSignals). Returns once every connection is
    // closed and every session's worker has stopped.
    void run();
    // Thread-safe; run() returns soon after.
    void stop();

    ServerCounters counters() const;

    struct Impl;  // Beast stays out of this header

private:
    std::unique_ptr<Impl> mImpl;
};

}  // namespace vdiso::serve
