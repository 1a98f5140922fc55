#include <cstdio>

#include "cli/args.h"
#include "cli/progress_bar.h"
#include "io/readers/raw_writer.h"
#include "io/readers/volume_open.h"
#include "io/store/store_writer.h"
#include "tools/commands.h"

namespace vdiso::cli {

namespace {

constexpr const char* kHelp =
    "usage: vdiso synth OUTPUT --kind head|turbulence --size N[,N,N] [options]\n"
    "\n"
    "Generates a deterministic test volume, streaming, on all cores. OUTPUT ending in .vdiso\n"
    "is written as a brick store, anything else as raw samples (x fastest, little-endian).\n"
    "\n"
    "  --kind head|turbulence  head: CT-like, skin at iso 600.5, bone at 1224.5;\n"
    "                          turbulence: noise with deep surfaces at its median\n"
    "  --size N | X,Y,Z        samples per axis\n"
    "  --type T                u8, i16, u16, f32 (default u16; head needs i16, u16 or f32)\n"
    "  --seed S                random seed (default 1)\n"
    "  --quiet                 no progress bar or summary\n"
    "store output (and --force for both):\n";

bool endsWithVdiso(const std::string& s) {
    return s.size() >= 6 && s.compare(s.size() - 6, 6, ".vdiso") == 0;
}

}  // namespace

int runSynth(int argc, char** argv) {
    Args args(argc, argv, 1);
    SynthParams params;
    StoreWriteOptions store;
    std::string outPath;
    bool kindGiven = false, sizeGiven = false, quiet = false;
    while (!args.done()) {
        const std::string a = args.take();
        if (a == "--help" || a == "-h") {
            std::fputs(kHelp, stdout);
            std::fputs(kStoreWriteOptionsHelp, stdout);
            return 0;
        } else if (a == "--kind") {
            const std::string k = args.value(a);
            if (k == "head") params.kind = SynthKind::Head;
            else if (k == "turbulence") params.kind = SynthKind::Turbulence;
            else throw UsageError("--kind expects head or turbulence, not '" + k + "'");
            kindGiven = true;
        } else if (a == "--size") {
            params.dims = parseDims(a, args.value(a));
            sizeGiven = true;
        } else if (a == "--type") {
            const std::string t = args.value(a);
            const auto type = parseScalarType(t);
            if (!type) throw UsageError("unknown type '" + t + "' (expected u8, i16, u16 or f32)");
            params.type = *type;
        } else if (a == "--seed") {
            params.seed = uint64_t(parseInt(a, args.value(a), 0, INT64_MAX));
        } else if (takeStoreWriteOption(a, args, store)) {
        } else if (a == "--quiet") {
            quiet = true;
        } else if (!a.empty() && a[0] == '-') {
            throw UsageError("unknown option '" + a + "'");
        } else if (outPath.empty()) {
            outPath = a;
        } else {
            throw UsageError("expects one OUTPUT");
        }
    }
    if (outPath.empty()) throw UsageError("expects OUTPUT");
    if (!kindGiven || !sizeGiven) throw UsageError("needs --kind and --size");
    if (params.kind == SynthKind::Head && params.type == ScalarType::U8)
        throw UsageError("a head needs i16, u16 or f32: u8 cannot hold its bone value 1224.5");

    auto source = openSynthVolume(params);
    const VolumeInfo& info = source->info();
    const ProgressFn progress = progressBar("synth", double(info.byteSize()), quiet);
    const auto& d = info.dims;
    if (endsWithVdiso(outPath)) {
        const StoreWriteSummary s = writeBrickStore(*source, outPath, store, progress);
        if (!quiet)
            std::printf("wrote %s: %lldx%lldx%lld %s store, %.1f MB, %.2f s\n", outPath.c_str(),
                        (long long)d[0], (long long)d[1], (long long)d[2],
                        scalarTypeName(info.type), s.fileBytes / 1e6, s.seconds);
    } else {
        const uint64_t bytes = writeRawVolume(*source, outPath, store.overwrite, progress);
        if (!quiet)
            std::printf("wrote %s: raw %.1f MB; convert with --dims %lld,%lld,%lld --type %s\n",
                        outPath.c_str(), bytes / 1e6, (long long)d[0], (long long)d[1],
                        (long long)d[2], scalarTypeName(info.type));
    }
    return 0;
}

}  // namespace vdiso::cli
