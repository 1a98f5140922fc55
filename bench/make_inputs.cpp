// vdiso_bench_inputs: writes the readers' benchmark inputs (bench/readers.sh) from the CT-like
// head, one format after another, streaming (bench/inputs/writers.h says what each holds).
//
//   vdiso_bench_inputs OUT_DIR [--raw data/head1024.raw | --synth N] [--only NAME,...]
//                      [--dicom-slices 1000] [--chunk 64] [--scales 1]
//
// An input already in OUT_DIR is kept; each is written as NAME.partial and renamed when
// complete, so an interrupted run leaves nothing that looks finished.
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <functional>
#include <set>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "bench/inputs/head_slices.h"
#include "bench/inputs/writers.h"

namespace {

namespace fs = std::filesystem;
using vdiso::bench::HeadSlices;

struct Input {
    const char* key;   // for --only
    const char* name;  // in OUT_DIR; bench/readers.sh knows these
    bool byDefault;    // the contiguous HDF5 file only when asked: 2 GiB more disk
    std::function<void(const HeadSlices&, const std::string&)> write;
};

const char* const kUsage =
    "usage: vdiso_bench_inputs OUT_DIR [--raw FILE | --synth N] [--only NAME,...]\n"
    "                          [--dicom-slices S] [--chunk C] [--scales L]\n"
    "  --raw FILE        the head as raw u16, N^3 samples, x fastest (data/head1024.raw)\n"
    "  --synth N         generate the head at N^3 instead (core/synth/synth.h; default 1024)\n"
    "  --only NAMES      dicom, dicom-jpeg, tiff, tiff-deflate, zarr, hdf5, hdf5-contig\n"
    "                    (default: all but hdf5-contig)\n"
    "  --dicom-slices S  slices of the DICOM series (default 1000)\n"
    "  --chunk C         Zarr and HDF5 chunk side (default 64)\n"
    "  --scales L        OME-Zarr levels: 0 and every 2^l-th sample for l < L (default 1)\n";

int run(int argc, char** argv) {
    std::string out, raw;
    int64_t synthSize = 1024, dicomSlices = 1000, chunk = 64;
    int scales = 1;
    std::set<std::string> only;
    for (int i = 1; i < argc; ++i) {
        const std::string a = argv[i];
        auto value = [&]() -> std::string {
            if (i + 1 >= argc) throw std::invalid_argument(a + " needs a value");
            return argv[++i];
        };
        if (a == "--help" || a == "-h") {
            std::fputs(kUsage, stdout);
            return 0;
        } else if (a == "--raw") {
            raw = value();
        } else if (a == "--synth") {
            synthSize = std::stoll(value());
        } else if (a == "--only") {
            std::stringstream list(value());
            for (std::string name; std::getline(list, name, ',');) only.insert(name);
        } else if (a == "--dicom-slices") {
            dicomSlices = std::stoll(value());
        } else if (a == "--chunk") {
            chunk = std::stoll(value());
        } else if (a == "--scales") {
            scales = std::stoi(value());
        } else if (!a.empty() && a[0] == '-') {
            throw std::invalid_argument("unknown option " + a);
        } else if (out.empty()) {
            out = a;
        } else {
            throw std::invalid_argument("expects one OUT_DIR");
        }
    }
    if (out.empty()) throw std::invalid_argument("expects OUT_DIR");
    if (chunk < 1 || synthSize < 2) throw std::invalid_argument("--chunk and --synth need a positive size");
    if (scales < 1 || scales > 16) throw std::invalid_argument("--scales needs 1 to 16 levels");

    using namespace vdiso::bench;
    const std::vector<Input> inputs = {
        {"dicom", "dicom", true,
         [&](const HeadSlices& h, const std::string& p) { writeDicomSeries(h, p, dicomSlices, false); }},
        {"dicom-jpeg", "dicom_jpegll", true,
         [&](const HeadSlices& h, const std::string& p) { writeDicomSeries(h, p, dicomSlices, true); }},
        {"tiff", "head.tif", true,
         [](const HeadSlices& h, const std::string& p) { writeTiffStack(h, p, false); }},
        {"tiff-deflate", "head_deflate.tif", true,
         [](const HeadSlices& h, const std::string& p) { writeTiffStack(h, p, true); }},
        {"zarr", "head.ome.zarr", true,
         [&](const HeadSlices& h, const std::string& p) { writeOmeZarr(h, p, chunk, scales); }},
        {"hdf5", "head.h5", true,
         [&](const HeadSlices& h, const std::string& p) { writeHdf5Volume(h, p, chunk); }},
        {"hdf5-contig", "head_contig.h5", false,
         [](const HeadSlices& h, const std::string& p) { writeHdf5Volume(h, p, 0); }},
    };
    for (const std::string& name : only) {
        bool known = false;
        for (const Input& in : inputs) known = known || name == in.key;
        if (!known) throw std::invalid_argument("--only: unknown input " + name);
    }

    fs::create_directories(out);
    const HeadSlices head(raw, synthSize);
    for (const Input& in : inputs) {
        if (only.empty() ? !in.byDefault : !only.count(in.key)) continue;
        const fs::path target = fs::path(out) / in.name;
        if (fs::exists(target)) {
            std::printf("%s: kept\n", target.c_str());
            continue;
        }
        const fs::path partial = target.string() + ".partial";
        fs::remove_all(partial);
        const auto start = std::chrono::steady_clock::now();
        in.write(head, partial.string());
        fs::rename(partial, target);
        const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
        std::printf("%s: written from %s in %.1f s\n", target.c_str(), head.name().c_str(), s);
        std::fflush(stdout);
    }
    return 0;
}

}  // namespace

int main(int argc, char** argv) {
    try {
        return run(argc, argv);
    } catch (const std::invalid_argument& e) {
        std::fprintf(stderr, "vdiso_bench_inputs: %s\n%s", e.what(), kUsage);
        return 2;
    } catch (const std::exception& e) {
        std::fprintf(stderr, "vdiso_bench_inputs: %s\n", e.what());
        return 1;
    }
}
