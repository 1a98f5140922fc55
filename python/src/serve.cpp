// vdiso.serve: `vdiso serve` inside the Python process, on its own thread, for a notebook.
#include <pybind11/stl.h>

#include <climits>
#include <memory>
#include <mutex>
#include <optional>
#include <thread>

#include "bindings.h"
#include "app/extract_settings.h"
#include "core/settings_error.h"
#include "serve/server.h"

namespace vdiso::py {

namespace pyb = pybind11;
using namespace pybind11::literals;

namespace {

class Server {
public:
    explicit Server(const serve::ServeOptions& options) {
        pyb::gil_scoped_release release;
        mServer = std::make_unique<serve::Server>(options);
        mThread = std::thread([server = mServer.get()] { server->run(); });
    }
    ~Server() { stop(); }
    std::string url() const { return mServer->url(); }
    uint16_t port() const { return mServer->port(); }
    bool running() const {
        std::lock_guard lock(mStopping);
        return mThread.joinable();
    }
    // From any number of threads at once: the first stops and joins, the others wait for it.
    void stop() {
        std::optional<pyb::gil_scoped_release> release;
        if (PyGILState_Check()) release.emplace();
        std::lock_guard lock(mStopping);
        if (!mThread.joinable()) return;
        mServer->stop();
        mThread.join();
    }

private:
    std::unique_ptr<serve::Server> mServer;
    std::thread mThread;
    mutable std::mutex mStopping;
};

}  // namespace

void bindServe(pyb::module_& m) {
    pyb::class_<Server>(m, "_Server")
        // Unset budgets and errors are the server's defaults (serve/serve_options.h), threads the
        // machine's cores as `vdiso serve` has them: one source for each.
        .def(pyb::init([](const std::vector<std::string>& stores, std::optional<double> iso, int64_t port,
                          const std::string& host, std::optional<int64_t> cacheMb, std::optional<int64_t> threads,
                          std::optional<double> lodError, const std::string& webRoot, int64_t maxViewers) {
                 serve::ServeOptions o;
                 o.stores = stores;
                 o.iso = iso;
                 o.port = uint16_t(checkedInt("port", port, 0, 65535));
                 o.host = host;
                 if (cacheMb) o.cacheBytes = uint64_t(checkedInt("cache_mb", *cacheMb, 1, int64_t(1) << 30)) << 20;
                 // Only what an int holds here: the range is the server's one check.
                 o.threads = threads ? int(checkedInt("threads", *threads, INT_MIN, INT_MAX)) : machineThreads();
                 if (lodError) o.lodError = *lodError;
                 o.webRoot = webRoot;
                 o.maxViewers = int(checkedInt("max_viewers", maxViewers, 0, 100000));  // 0: by memory
                 return std::make_unique<Server>(o);
             }),
             "stores"_a, "iso"_a, "port"_a, "host"_a, "cache_mb"_a, "threads"_a, "lod_error"_a, "web_root"_a, "max_viewers"_a = 0)
        .def_property_readonly("url", &Server::url)
        .def_property_readonly("port", &Server::port)
        .def_property_readonly("running", &Server::running)
        .def("stop", &Server::stop);
}

}  // namespace vdiso::py
