// vdiso: view-dependent isosurface extraction from bricked volumes.
#include <cstdio>
#include <cstring>
#include <exception>
#include <string>

#include "cli/args.h"
#include "cli/progress_bar.h"
#include "core/interrupt.h"
#include "io/error.h"
#include "tools/commands.h"

namespace {

constexpr const char* kUsage =
    "usage: vdiso <command> [options]\n"
    "\n"
    "commands:\n"
    "  convert INPUT OUTPUT.vdiso   convert a raw, NRRD, NIfTI or OpenVDB volume into a brick store\n"
    "  index DATA                   index a Zarr or OME-Zarr array where it lies: then every\n"
    "                               command opens DATA like a store, without converting it\n"
    "  synth OUTPUT                 generate a test volume (head, turbulence) as raw or a store\n"
    "  info FILE.vdiso              describe a brick store; with --iso, its active bricks\n"
    "  extract FILE.vdiso --iso V   extract an isosurface: mesh, picture, statistics\n"
    "  compare A.png B.png          how much of A's rendered surface B reproduces\n"
    "  serve FILE.vdiso ...         look around isosurfaces from a browser: streams the visible\n"
    "                               surface as the camera moves\n"
    "\n"
    "'vdiso <command> --help' describes each command.\n";

}  // namespace

int main(int argc, char** argv) {
    using namespace vdiso::cli;
    if (argc < 2 || !std::strcmp(argv[1], "--help") || !std::strcmp(argv[1], "-h")) {
        std::fputs(kUsage, argc < 2 ? stderr : stdout);
        return argc < 2 ? 2 : 0;
    }
    installInterruptHandler();
    const std::string command = argv[1];
    try {
        if (command == "convert") return runConvert(argc - 1, argv + 1);
        if (command == "index") return runIndex(argc - 1, argv + 1);
        if (command == "synth") return runSynth(argc - 1, argv + 1);
        if (command == "info") return runInfo(argc - 1, argv + 1);
        if (command == "extract") return runExtract(argc - 1, argv + 1);
        if (command == "compare") return runCompare(argc - 1, argv + 1);
        if (command == "serve") return runServe(argc - 1, argv + 1);
        std::fprintf(stderr, "vdiso: unknown command '%s'\n\n%s", command.c_str(), kUsage);
        return 2;
    } catch (const std::exception& e) {
        const int code = exitCodeOf(e);
        if (code == 2)
            std::fprintf(stderr, "vdiso %s: %s (see 'vdiso %s --help')\n", command.c_str(), messageOf(e).c_str(),
                         command.c_str());
        else if (code == 130)  // Ctrl-C or SIGTERM, seen by a library loop: its output was removed
            std::fprintf(stderr, "\nvdiso %s: %s; no output written\n", command.c_str(), e.what());
        else
            std::fprintf(stderr, "vdiso %s: error: %s\n", command.c_str(), messageOf(e).c_str());
        return code;
    }
}
