// Zarr arrays written by hand after the Zarr v2/v3 specifications, for the Zarr reader's and
// the index's tests (test_zarr.cpp, test_zarr_index.cpp): u16 samples, any chunk shape, every
// codec vdiso reads, chunks left out on request.
#pragma once

#include <cstdint>
#include <filesystem>
#include <functional>
#include <string>
#include <vector>

#include "core/volume.h"

namespace vdiso {
class BrickStoreReader;
}

namespace vdiso::test {

enum class Codec { None, Blosc, Zstd, Gzip };

// The bytes `raw` compressed as `codec` stores them.
std::string compress(const std::string& raw, Codec codec);

// The default samples: sample (x, y, z) of a u16 volume, different in every position.
double zarrTestValue(int64_t x, int64_t y, int64_t z);

// An array of u16 samples (x, y, z) = sample(x*step, ...), shape (z, y, x) with leading axes of
// size 1 when `extraAxes`, chunked by `chunk` (z, y, x); `skip` says which chunks to leave out.
struct ArraySpec {
    int format = 2;
    Dims3 dims{13, 10, 9};           // x, y, z
    std::vector<int64_t> chunk{4, 4, 5};  // z, y, x
    Codec codec = Codec::Blosc;
    char separator = '.';
    bool bigEndian = false;
    int extraAxes = 0;
    int step = 1;
    double fill = 0;
    std::function<bool(int64_t, int64_t, int64_t)> skip;
    std::function<double(int64_t, int64_t, int64_t)> sample = zarrTestValue;
    // Zarr v3 only: shards of this shape (z, y, x, a multiple of `chunk`), each holding its
    // inner chunks (`chunk`) and an index at its end with its CRC-32C; skipped inner chunks are
    // not stored. Empty: not sharded.
    std::vector<int64_t> shard;
};

// Writes the array's metadata and chunks into `dir` (created).
void writeArray(const std::filesystem::path& dir, const ArraySpec& a);

// Expects an index (vdiso index) to open as `store` does, level for level: the same levels,
// entries' ranges, sub-block codes, histogram and every brick's samples.
void expectSameStore(const BrickStoreReader& index, const BrickStoreReader& store, const std::string& what);

}  // namespace vdiso::test
