// Helpers shared by the tests: a scratch directory, files, running the vdiso binary, and an
// in-memory volume that plays SliceReader.
#pragma once

#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <string>
#include <vector>

#include "io/store/brick_store.h"
#include "io/readers/slice_reader.h"

// Built with AddressSanitizer: its shadow memory takes terabytes of address space, so tests that
// run under an address-space limit (ulimit -v) cannot run.
#if defined(__SANITIZE_ADDRESS__)
#define VDISO_UNDER_ASAN 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define VDISO_UNDER_ASAN 1
#endif
#endif
#ifndef VDISO_UNDER_ASAN
#define VDISO_UNDER_ASAN 0
#endif

namespace vdiso::test {

// A fresh directory under the system temp dir, removed with the object.
class ScratchDir {
public:
    ScratchDir();
    ~ScratchDir();
    std::string file(const std::string& name) const { return (mPath / name).string(); }
    const std::filesystem::path& path() const { return mPath; }

private:
    std::filesystem::path mPath;
};

void writeFile(const std::string& path, const void* data, size_t n);
inline void writeFile(const std::string& path, const std::string& text) {
    writeFile(path, text.data(), text.size());
}
std::vector<unsigned char> readFile(const std::string& path);
inline std::string readText(const std::string& path) {
    const std::vector<unsigned char> bytes = readFile(path);
    return std::string(bytes.begin(), bytes.end());
}

struct CommandResult {
    int exitCode = -1;
    std::string output;  // stdout and stderr together
};
// Runs a shell command line, stdout and stderr together.
CommandResult runCommand(const std::string& line);
// Runs build/bin/vdiso with `args` (a shell-quoted string).
CommandResult runVdiso(const std::string& args);

// $VDISO_DATA_DIR/name (the real data scripts/fetch_data.sh puts there), or "" when it is not
// there: the test then skips.
std::string dataFile(const char* name);

// A deterministic pseudo-random value for sample index i: spreads over the type's range so
// every bit of every sample is exercised.
double testSampleValue(ScalarType type, uint64_t i);

// A volume held in memory, served slice by slice.
class MemoryVolume final : public SliceReader {
public:
    MemoryVolume(const Dims3& dims, ScalarType type);
    const VolumeInfo& info() const override { return mInfo; }
    void read(void* dst, int64_t count) override;
    std::string name() const override { return "memory"; }
    // Gives the volume a physical placement, as a reader of an oriented format does.
    void orient(const glm::dvec3& origin, const glm::dmat3& direction) {
        mInfo.origin = origin;
        mInfo.direction = direction;
        mInfo.hasOrientation = true;
    }

    // Sample (x,y,z) as a double.
    double at(int64_t x, int64_t y, int64_t z) const;
    const std::vector<unsigned char>& bytes() const { return mBytes; }
    std::vector<unsigned char>& bytes() { return mBytes; }  // to write samples of one's own

private:
    VolumeInfo mInfo;
    std::vector<unsigned char> mBytes;
    int64_t mNextZ = 0;
};

// A u16 ball (radius 24 about the centre of 96^3, 1000 inside, 100 outside) beside a plate one
// voxel thick (y = 72 + x / 4 + z / 10 rounded, x in [8, 56), z in [8, 88)), isovalue 550: the
// coarse levels of detail lose the plate (core/lod/thin_parts.h).
void fillBallBesidePlate(MemoryVolume& volume);  // volume: 96^3 u16

// Reads everything a source delivers, in slabs of `slab` slices (uneven on purpose).
std::vector<unsigned char> readAllSamples(SliceReader& source, int64_t slab = 3);

// A store file's bytes with its index edited as raw bytes (docs/store-format.md, "Index"): the
// index is unpacked, `edit` changes it, and it is packed again (or, with repack false, left
// raw as stores before version 5 hold it); the header's index size and checksums follow.
std::vector<unsigned char> rewriteStoreIndex(std::vector<unsigned char> bytes,
                                             const std::function<void(std::vector<unsigned char>&)>& edit,
                                             bool repack = true);

// A store file's bytes as an older version (2 to 4) wrote them: the index raw, the version, the
// level count (reserved, 0, in version 2), zero bytes after the header's first checksum, that
// checksum recomputed.
std::vector<unsigned char> storeAsVersion(std::vector<unsigned char> bytes, uint32_t version);

// Compares every stored sample of every brick of level `level` (ghosts included, clamped at the
// borders) with `samples` (the whole level, x fastest), and each brick's index min/max with
// brute force. Returns "" when all agree, else a description of the first difference.
std::string compareStoreWithSamples(const BrickStoreReader& store,
                                    const std::vector<unsigned char>& samples, int level = 0);

// The next level of detail of `samples` (`dims` of `type`, x fastest), by brute force: every
// coarse sample from its 27 fine neighbours (core/lod/downsample.h's tent, indices clamped), summed
// in the same order so that floats agree to the bit. `dims` becomes the coarse level's.
std::vector<unsigned char> bruteForceLevel(const std::vector<unsigned char>& samples, Dims3& dims,
                                           ScalarType type);

}  // namespace vdiso::test
