// An OME-Zarr 0.4 image written by hand (the format is JSON and a file per chunk), as
// tests/test_zarr.cpp writes its small ones: a layer of chunks at a time.
#include <blosc.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <stdexcept>
#include <vector>

#include "bench/inputs/writers.h"

namespace vdiso::bench {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

void writeFile(const fs::path& path, const void* data, size_t bytes) {
    std::ofstream out(path, std::ios::binary);
    if (!out.write(static_cast<const char*>(data), std::streamsize(bytes)) || !out.flush())
        throw std::runtime_error(path.string() + ": cannot write it");
}

void writeJson(const fs::path& path, const json& j) {
    const std::string text = j.dump(2);
    writeFile(path, text.data(), text.size());
}

}  // namespace

void writeOmeZarr(const HeadSlices& head, const std::string& folder, int64_t chunk, int scales) {
    const int64_t n = head.size();
    const fs::path root(folder);
    fs::create_directories(root);
    writeJson(root / ".zgroup", {{"zarr_format", 2}});
    const json axis = {{"type", "space"}, {"unit", "micrometer"}};
    json axes = json::array();
    for (const char* name : {"z", "y", "x"}) {
        json a = axis;
        a["name"] = name;
        axes.push_back(a);
    }
    json datasets = json::array();
    for (int l = 0; l < scales; ++l) {
        const double step = double(int64_t(1) << l);
        json scale = json::object();
        scale["type"] = "scale";
        scale["scale"] = {step, step, step};
        json dataset = json::object();
        dataset["path"] = std::to_string(l);
        dataset["coordinateTransformations"] = json::array({scale});
        datasets.push_back(dataset);
    }
    json image = json::object();
    image["version"] = "0.4";
    image["name"] = "head";
    image["axes"] = axes;
    image["datasets"] = datasets;
    json attributes = json::object();
    attributes["multiscales"] = json::array({image});
    writeJson(root / ".zattrs", attributes);

    const size_t chunkSamples = size_t(chunk * chunk * chunk);
    std::vector<uint16_t> full(size_t(n * n)), samples(chunkSamples);
    std::vector<char> stored(chunkSamples * 2 + BLOSC_MAX_OVERHEAD);
    for (int l = 0; l < scales; ++l) {
        // Scale l: every 2^l-th sample of the head on each axis, ceil(n / 2^l) of them.
        const int64_t step = int64_t(1) << l, m = (n + step - 1) / step;
        const fs::path array = root / std::to_string(l);
        fs::create_directories(array);
        writeJson(array / ".zarray", {{"zarr_format", 2},
                                      {"shape", {m, m, m}},
                                      {"chunks", {chunk, chunk, chunk}},
                                      {"dtype", "<u2"},
                                      {"compressor",
                                       {{"id", "blosc"}, {"cname", "lz4"}, {"clevel", 5},
                                        {"shuffle", 1}, {"blocksize", 0}}},
                                      {"fill_value", 0},
                                      {"order", "C"},
                                      {"filters", nullptr},
                                      {"dimension_separator", "/"}});
        std::vector<uint16_t> slab(size_t(chunk * m * m));
        for (int64_t z0 = 0; z0 < m; z0 += chunk) {
            const int64_t depth = std::min(chunk, m - z0);
            if (step == 1) {
                head.read(z0, depth, slab.data());
            } else {
                for (int64_t z = 0; z < depth; ++z) {
                    head.read((z0 + z) * step, 1, full.data());
                    uint16_t* out = slab.data() + size_t(z * m * m);
                    for (int64_t y = 0; y < m; ++y)
                        for (int64_t x = 0; x < m; ++x) out[y * m + x] = full[size_t((y * n + x) * step)];
                }
            }
            for (int64_t y0 = 0; y0 < m; y0 += chunk)
                for (int64_t x0 = 0; x0 < m; x0 += chunk) {
                    // Edge chunks are whole in the file, padded with the fill value.
                    std::fill(samples.begin(), samples.end(), uint16_t(0));
                    const int64_t rows = std::min(chunk, m - y0), cols = std::min(chunk, m - x0);
                    for (int64_t z = 0; z < depth; ++z)
                        for (int64_t y = 0; y < rows; ++y)
                            std::copy_n(slab.data() + size_t((z * m + y0 + y) * m + x0), cols,
                                        samples.data() + size_t((z * chunk + y) * chunk));
                    const int bytes = blosc_compress_ctx(5, BLOSC_SHUFFLE, 2, chunkSamples * 2,
                                                         samples.data(), stored.data(), stored.size(),
                                                         "lz4", 0, 1);
                    const fs::path file = array / std::to_string(z0 / chunk) /
                                          std::to_string(y0 / chunk) / std::to_string(x0 / chunk);
                    if (bytes <= 0) throw std::runtime_error(file.string() + ": blosc cannot compress it");
                    fs::create_directories(file.parent_path());
                    writeFile(file, stored.data(), size_t(bytes));
                }
        }
    }
}

}  // namespace vdiso::bench
