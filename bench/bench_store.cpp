// Micro-benchmarks of the brick store's hot paths: generating slabs, converting, and reading
// bricks back (checksum + zstd decode), on a generated head written to a temporary store.
#include <benchmark/benchmark.h>

#include <filesystem>
#include <vector>

#include <unistd.h>

#include "io/store/brick_store.h"
#include "io/store/store_writer.h"
#include "io/readers/volume_open.h"

namespace {

using namespace vdiso;

std::string storePath(Compression c) {
    static const std::string base =
        (std::filesystem::temp_directory_path() / ("vdiso_bench_" + std::to_string(::getpid()))).string();
    const std::string path = base + (c == Compression::Zstd ? "_zstd.vdiso" : "_none.vdiso");
    if (!std::filesystem::exists(path)) {
        SynthParams p;
        p.dims = {256, 256, 256};
        auto src = openSynthVolume(p);
        StoreWriteOptions o;
        o.compression = c;
        writeBrickStore(*src, path, o);
    }
    return path;
}

void BM_SynthHeadSlab(benchmark::State& state) {
    SynthParams p;
    p.dims = {256, 256, 256};
    std::vector<uint16_t> slab(size_t(256) * 256 * 35);
    int64_t z = 0;
    for (auto _ : state) {
        synthesizeSlices(p, z, 35, slab.data());
        z = (z + 35) % (256 - 35);
    }
    state.SetBytesProcessed(int64_t(state.iterations()) * int64_t(slab.size() * 2));
}
BENCHMARK(BM_SynthHeadSlab)->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_ConvertHead256(benchmark::State& state) {
    const std::string out = storePath(Compression::Zstd) + ".convert";
    for (auto _ : state) {
        SynthParams p;
        p.dims = {256, 256, 256};
        auto src = openSynthVolume(p);
        StoreWriteOptions o;
        o.overwrite = true;
        writeBrickStore(*src, out, o);
    }
    std::filesystem::remove(out);
    state.SetBytesProcessed(int64_t(state.iterations()) * 256 * 256 * 256 * 2);
}
BENCHMARK(BM_ConvertHead256)->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_ReadBrick(benchmark::State& state) {
    const BrickStoreReader store(storePath(Compression(state.range(0))));
    std::vector<unsigned char> brick(store.brickBytes());
    int64_t id = 0;
    for (auto _ : state) {
        store.readBrick(id, brick.data());
        id = (id + 1) % store.layout().brickCount();
    }
    state.SetBytesProcessed(int64_t(state.iterations()) * int64_t(brick.size()));
    state.SetLabel(compressionName(store.header().compression));
}
BENCHMARK(BM_ReadBrick)->Arg(int(Compression::Zstd))->Arg(int(Compression::None));

}  // namespace

int main(int argc, char** argv) {
    benchmark::Initialize(&argc, argv);
    benchmark::RunSpecifiedBenchmarks();
    for (Compression c : {Compression::Zstd, Compression::None})
        std::filesystem::remove(storePath(c));
    return 0;
}
