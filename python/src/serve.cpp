// vdiso.serve: `vdiso serve` inside the Python process, on its own thread, for a notebook.
#include <pybind11/stl.h>

#include <memory>
#include <optional>
#include <thread>

#include "bindings.h"
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
    bool running() const { return mThread.joinable(); }
    void stop() {
        if (!mThread.joinable()) return;
        std::optional<pyb::gil_scoped_release> release;
        if (PyGILState_Check()) release.emplace();
        mServer->stop();
        mThread.join();
    }

private:
    std::unique_ptr<serve::Server> mServer;
    std::thread mThread;
};

}  // namespace

void bindServe(pyb::module_& m) {
    pyb::class_<Server>(m, "_Server")
        .def(pyb::init([](const std::vector<std::string>& stores, std::optional<double> iso, int port,
                          const std::string& host, uint64_t cacheMb, int threads, double lodError,
                          const std::string& webRoot, int maxViewers) {
                 if (port < 0 || port > 65535) throw SettingsError("port", "expects 0 to 65535, not " + std::to_string(port));
                 serve::ServeOptions o;
                 o.stores = stores;
                 o.iso = iso;
                 o.port = uint16_t(port);
                 o.host = host;
                 o.cacheBytes = cacheMb << 20;
                 o.threads = threads;
                 o.lodError = lodError;
                 o.webRoot = webRoot;
                 o.maxViewers = maxViewers;
                 return std::make_unique<Server>(o);
             }),
             "stores"_a, "iso"_a, "port"_a, "host"_a, "cache_mb"_a, "threads"_a, "lod_error"_a, "web_root"_a, "max_viewers"_a = 0)
        .def_property_readonly("url", &Server::url)
        .def_property_readonly("port", &Server::port)
        .def_property_readonly("running", &Server::running)
        .def("stop", &Server::stop);
}

}  // namespace vdiso::py
