#include <cstdio>
#include <limits>
#include <string>

#include "app/extract_settings.h"
#include "cli/args.h"
#include "serve/server.h"
#include "tools/commands.h"

namespace vdiso::cli {

namespace {

constexpr const char* kHelp =
    "usage: vdiso serve STORE.vdiso [MORE.vdiso ...] [options]\n"
    "\n"
    "Serves a browser viewer that looks around the stores' isosurfaces: for each camera the\n"
    "browser sends, the surface it sees is extracted (SAGE) and streamed front to back, and\n"
    "only what the browser does not hold already goes over the network. Prints the URL to\n"
    "open (with its access token) and serves until Ctrl-C.\n"
    "\n"
    "  --iso V             the isovalue the viewer starts at (default: Otsu's threshold of\n"
    "                      each store's histogram)\n"
    "  --host ADDRESS      the address to listen on (default 127.0.0.1: this machine only)\n"
    "  --port N            the port (default 8080; 0: any free port)\n"
    "  --cache-mb N        brick cache shared by every client, in MB (default 1024)\n"
    "  --chunk-cache-mb N  encoded chunks kept for every client, in MB (default 256; 0:\n"
    "                      none, each viewer's frames encode their own)\n"
    "  --threads N         extraction threads per frame: image strips (default: the\n"
    "                      machine's cores)\n"
    "  --metacell M        meta-cell size in cells, 1 to 32 (default 8)\n"
    "  --lod-error P       levels of detail: each frame's surface is extracted where it is\n"
    "                      nearest at the coarsest level whose cells span at most P pixels\n"
    "                      (default 1; 0: full resolution only); on stores with levels a\n"
    "                      frame 8x coarser comes first, and the viewer refines from it\n"
    "  --max-viewers N     viewers at once; one more is answered 503 (default: what the\n"
    "                      memory beside the cache holds at 96 MB a viewer, 4 to 256)\n"
    "  --token T           the access token (default: random at each start)\n"
    "  --web DIR           the viewer's folder (default: the source tree's web/)\n";

}  // namespace

// Numbers are only read here; their ranges are the server's (serve::checkServeOptions).
constexpr int64_t kIntMin = std::numeric_limits<int>::min(), kIntMax = std::numeric_limits<int>::max();

int runServe(int argc, char** argv) {
    Args args(argc, argv, 1);
    serve::ServeOptions o;
    o.webRoot = VDISO_WEB_DIR;
    o.handleSignals = true;
    o.threads = vdiso::machineThreads();
    while (!args.done()) {
        const std::string a = args.take();
        if (a == "--help" || a == "-h") {
            std::fputs(kHelp, stdout);
            std::fputs(kRemoteOptionsHelp, stdout);
            return 0;
        } else if (a == "--iso") {
            o.iso = parseDouble(a, args.value(a));
        } else if (a == "--host") {
            o.host = args.value(a);
        } else if (a == "--port") {
            o.port = uint16_t(parseInt(a, args.value(a), 0, 65535));
        } else if (a == "--cache-mb") {
            o.cacheBytes = uint64_t(parseInt(a, args.value(a), 1, int64_t(1) << 30)) << 20;
        } else if (a == "--chunk-cache-mb") {
            o.chunkCacheBytes = uint64_t(parseInt(a, args.value(a), 0, int64_t(1) << 30)) << 20;
        } else if (a == "--max-viewers") {
            o.maxViewers = int(parseInt(a, args.value(a), kIntMin, kIntMax));
        } else if (a == "--threads") {
            o.threads = int(parseInt(a, args.value(a), kIntMin, kIntMax));
        } else if (a == "--lod-error") {
            o.lodError = parseDouble(a, args.value(a));
        } else if (a == "--metacell") {
            o.metaCellSize = int(parseInt(a, args.value(a), kIntMin, kIntMax));
        } else if (a == "--token") {
            o.token = args.value(a);
        } else if (a == "--web") {
            o.webRoot = args.value(a);
        } else if (takeRemoteOption(a, args, o.remote)) {
        } else if (!a.empty() && a[0] == '-') {
            throw UsageError("unknown option '" + a + "'");
        } else {
            o.stores.push_back(a);
        }
    }
    if (o.stores.empty()) throw UsageError("expects at least one STORE.vdiso");
    serve::Server server(o);  // checks the options (SettingsError, named as flags) before opening a store
    std::printf("vdiso serve: open %s\n", server.url().c_str());
    std::fflush(stdout);
    server.run();
    std::fprintf(stderr, "vdiso serve: stopped\n");
    return 0;
}

}  // namespace vdiso::cli
