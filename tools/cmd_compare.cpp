#include <cstdio>

#include "cli/args.h"
#include "io/render/image_compare.h"
#include "io/render/png_image.h"
#include "tools/commands.h"

namespace vdiso::cli {

namespace {

constexpr const char* kHelp =
    "usage: vdiso compare REFERENCE.png OTHER.png [--tolerance T] [--min F]\n"
    "\n"
    "How much of the reference rendering's surface the other reproduces: of the pixels the\n"
    "reference covers (not its border's background colour), the fraction the other covers\n"
    "with a colour within T per channel (default 24 of 255). With --min F, exits 1 when the\n"
    "agreement is below F (e.g. 0.995).\n";

}  // namespace

int runCompare(int argc, char** argv) {
    Args args(argc, argv, 1);
    std::vector<std::string> paths;
    int tolerance = 24;
    double minimum = -1;
    while (!args.done()) {
        const std::string a = args.take();
        if (a == "--help" || a == "-h") {
            std::fputs(kHelp, stdout);
            return 0;
        } else if (a == "--tolerance") {
            tolerance = int(parseInt(a, args.value(a), 0, 255));
        } else if (a == "--min") {
            minimum = parseDouble(a, args.value(a));
        } else if (!a.empty() && a[0] == '-') {
            throw UsageError("unknown option '" + a + "'");
        } else {
            paths.push_back(a);
        }
    }
    if (paths.size() != 2) throw UsageError("expects REFERENCE.png and OTHER.png");
    const RgbaImage reference = readPng(paths[0]), other = readPng(paths[1]);
    const ImageAgreement r = compareImages(reference, other, tolerance);
    std::printf("agreement %.5f: %llu of %llu covered pixels (%llu missing, %llu of another "
                "colour; %llu extra)\n",
                r.agreement(), (unsigned long long)r.agreeing,
                (unsigned long long)r.referenceCovered, (unsigned long long)r.missing,
                (unsigned long long)r.differentColour, (unsigned long long)r.extra);
    return minimum >= 0 && r.agreement() < minimum ? 1 : 0;
}

}  // namespace vdiso::cli
