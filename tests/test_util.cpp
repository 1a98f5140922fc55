#include "tests/test_util.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <random>
#include <stdexcept>
#include <type_traits>

#include <sys/wait.h>
#include <unistd.h>

#include "io/crc32.h"
#include "io/store/index_parts.h"
#include "io/store/store_format.h"

namespace vdiso::test {

std::string dataFile(const char* name) {
    const char* dir = std::getenv("VDISO_DATA_DIR");
    if (!dir) return "";
    const std::string path = std::string(dir) + "/" + name;
    return std::filesystem::exists(path) ? path : "";
}

ScratchDir::ScratchDir() {
    // A new directory every time (mkdtemp): one named by the process id could be an old one
    // left by a killed test, files and all, once the ids wrap (pid_max is 32768 here), and a
    // test would then find outputs it has not written.
    std::string pattern = (std::filesystem::temp_directory_path() / "vdiso_test_XXXXXX").string();
    if (!::mkdtemp(pattern.data())) throw std::runtime_error("cannot make a scratch directory in " + pattern);
    mPath = pattern;
}

ScratchDir::~ScratchDir() {
    std::error_code ec;
    std::filesystem::remove_all(mPath, ec);
}

void writeFile(const std::string& path, const void* data, size_t n) {
    std::ofstream f(path, std::ios::binary | std::ios::trunc);
    f.write(static_cast<const char*>(data), std::streamsize(n));
    if (!f) throw std::runtime_error("cannot write test file " + path);
}

std::vector<unsigned char> readFile(const std::string& path) {
    std::ifstream f(path, std::ios::binary);
    return std::vector<unsigned char>(std::istreambuf_iterator<char>(f), {});
}

CommandResult runCommand(const std::string& line) {
    const std::string command = "( " + line + " ) 2>&1";
    CommandResult r;
    FILE* pipe = ::popen(command.c_str(), "r");
    if (!pipe) throw std::runtime_error("cannot run " + command);
    std::array<char, 4096> buf;
    size_t n;
    while ((n = std::fread(buf.data(), 1, buf.size(), pipe)) > 0) r.output.append(buf.data(), n);
    const int status = ::pclose(pipe);
    r.exitCode = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
    return r;
}

CommandResult runVdiso(const std::string& args) { return runCommand(std::string(VDISO_BINARY) + " " + args); }

double testSampleValue(ScalarType type, uint64_t i) {
    uint64_t h = (i + 1) * 0x9E3779B97F4A7C15ull;
    h ^= h >> 31;
    h *= 0xBF58476D1CE4E5B9ull;
    h ^= h >> 29;
    switch (type) {
        case ScalarType::U8: return double(h & 0xff);
        case ScalarType::I16: return double(int16_t(h & 0xffff));
        case ScalarType::U16: return double(h & 0xffff);
        case ScalarType::F32: break;
    }
    return double(float(int64_t(h % 2000001) - 1000000) / 7.0f);
}

MemoryVolume::MemoryVolume(const Dims3& dims, ScalarType type) {
    mInfo.dims = dims;
    mInfo.type = type;
    mBytes.resize(mInfo.byteSize());
    visitScalarType(type, [&](auto zero) {
        using T = decltype(zero);
        T* p = reinterpret_cast<T*>(mBytes.data());
        for (int64_t i = 0; i < mInfo.sampleCount(); ++i) p[i] = T(testSampleValue(type, uint64_t(i)));
    });
}

void MemoryVolume::read(void* dst, int64_t count) {
    const size_t sliceBytes = size_t(mInfo.sliceSamples()) * scalarSize(mInfo.type);
    if (mNextZ + count > mInfo.dims[2]) throw std::runtime_error("read past the end");
    std::memcpy(dst, mBytes.data() + size_t(mNextZ) * sliceBytes, size_t(count) * sliceBytes);
    mNextZ += count;
}

void fillBallBesidePlate(MemoryVolume& volume) {
    const Dims3& dims = volume.info().dims;
    uint16_t* v = reinterpret_cast<uint16_t*>(volume.bytes().data());
    for (int64_t z = 0; z < dims[2]; ++z)
        for (int64_t y = 0; y < dims[1]; ++y)
            for (int64_t x = 0; x < dims[0]; ++x) {
                const double r = std::hypot(x - 48.0, y - 48.0, z - 48.0);
                const bool plate = y == std::lround(72 + 0.25 * x + 0.1 * z) && x >= 8 && x < 56 && z >= 8 && z < 88;
                v[(z * dims[1] + y) * dims[0] + x] = plate || r < 24 ? 1000 : 100;
            }
}

double MemoryVolume::at(int64_t x, int64_t y, int64_t z) const {
    const int64_t i = x + mInfo.dims[0] * (y + mInfo.dims[1] * z);
    return visitScalarType(mInfo.type, [&](auto zero) {
        using T = decltype(zero);
        T v;
        std::memcpy(&v, mBytes.data() + size_t(i) * sizeof(T), sizeof(T));
        return double(v);
    });
}

std::vector<unsigned char> readAllSamples(SliceReader& source, int64_t slab) {
    const VolumeInfo& info = source.info();
    std::vector<unsigned char> out(info.byteSize());
    const size_t sliceBytes = size_t(info.sliceSamples()) * scalarSize(info.type);
    for (int64_t z = 0; z < info.dims[2]; z += slab)
        source.read(out.data() + size_t(z) * sliceBytes, std::min(slab, info.dims[2] - z));
    source.finish();
    return out;
}

std::string compareStoreWithSamples(const BrickStoreReader& store,
                                    const std::vector<unsigned char>& samples, int level) {
    const BrickLayout& l = store.levels().at(size_t(level)).layout;
    const int64_t first = store.levels()[size_t(level)].firstBrick;
    const Dims3& d = l.dims;
    std::vector<unsigned char> brick(store.brickBytes());
    return visitScalarType(store.volume().type, [&](auto zero) -> std::string {
        using T = decltype(zero);
        const T* volume = reinterpret_cast<const T*>(samples.data());
        for (int64_t id = 0; id < l.brickCount(); ++id) {
            store.readBrick(first + id, brick.data());
            const Dims3 c = l.brickCoord(id);
            const T* s = reinterpret_cast<const T*>(brick.data());
            // Per axis, once a brick: each local sample's clamped volume coordinate, and
            // whether it is a corner of one of the brick's own cells.
            std::array<std::vector<int64_t>, 3> at;
            std::array<std::vector<char>, 3> corner;
            for (int a = 0; a < 3; ++a)
                for (int k = 0; k < l.side(); ++k) {
                    at[size_t(a)].push_back(l.clampSample(a, l.firstSample(c[size_t(a)]) + k));
                    corner[size_t(a)].push_back(k >= 1 && k <= 1 + l.cellsOnAxis(a, c[size_t(a)]));
                }
            double lo = INFINITY, hi = -INFINITY;
            for (int lz = 0; lz < l.side(); ++lz)
                for (int ly = 0; ly < l.side(); ++ly) {
                    const T* expectedRow = volume + d[0] * (at[1][size_t(ly)] + d[1] * at[2][size_t(lz)]);
                    const T* gotRow = s + (size_t(lz) * l.side() + ly) * l.side();
                    const bool cornerRow = corner[1][size_t(ly)] && corner[2][size_t(lz)];
                    for (int lx = 0; lx < l.side(); ++lx) {
                        const T expected = expectedRow[at[0][size_t(lx)]];
                        const T got = gotRow[lx];
                        const bool bothNaN = got != got && expected != expected;
                        if (std::memcmp(&got, &expected, sizeof(T)) != 0 && !bothNaN)
                            return "brick " + std::to_string(id) + " sample " + std::to_string(lx) + "," +
                                   std::to_string(ly) + "," + std::to_string(lz) + ": " +
                                   std::to_string(double(got)) + " != " + std::to_string(double(expected));
                        if (cornerRow && corner[0][size_t(lx)]) {
                            lo = std::min(lo, double(expected));
                            hi = std::max(hi, double(expected));
                        }
                    }
                }
            const BrickEntry& e = store.index()[size_t(first + id)];
            if (double(e.minValue) != double(float(lo)) || double(e.maxValue) != double(float(hi)))
                return "brick " + std::to_string(id) + " index range [" +
                       std::to_string(e.minValue) + ", " + std::to_string(e.maxValue) +
                       "] != [" + std::to_string(lo) + ", " + std::to_string(hi) + "]";
        }
        return "";
    });
}

std::vector<unsigned char> bruteForceLevel(const std::vector<unsigned char>& samples, Dims3& dims,
                                           ScalarType type) {
    const Dims3 fine = dims;
    for (int a = 0; a < 3; ++a) dims[a] = (fine[a] - 1 + 1) / 2 + 1;
    std::vector<unsigned char> out(size_t(dims[0] * dims[1] * dims[2]) * scalarSize(type));
    visitScalarType(type, [&](auto zero) {
        using T = decltype(zero);
        const T* in = reinterpret_cast<const T*>(samples.data());
        T* o = reinterpret_cast<T*>(out.data());
        const float tent[3] = {0.25f, 0.5f, 0.25f};
        auto clamp = [](int64_t v, int64_t n) { return std::clamp<int64_t>(v, 0, n - 1); };
        for (int64_t z = 0; z < dims[2]; ++z)
            for (int64_t y = 0; y < dims[1]; ++y)
                for (int64_t x = 0; x < dims[0]; ++x) {
                    float column[3];
                    for (int dx = 0; dx < 3; ++dx) {
                        const int64_t fx = clamp(2 * x + dx - 1, fine[0]);
                        column[dx] = 0.0f;
                        for (int dz = 0; dz < 3; ++dz)
                            for (int dy = 0; dy < 3; ++dy) {
                                const int64_t fz = clamp(2 * z + dz - 1, fine[2]), fy = clamp(2 * y + dy - 1, fine[1]);
                                column[dx] += tent[dz] * tent[dy] * float(in[fx + fine[0] * (fy + fine[1] * fz)]);
                            }
                    }
                    const float v = 0.25f * column[0] + 0.5f * column[1] + 0.25f * column[2];
                    T r;
                    if constexpr (std::is_floating_point_v<T>) r = T(v);
                    else r = T(std::floor(v + 0.5f));
                    o[x + dims[0] * (y + dims[1] * z)] = r;
                }
    });
    return out;
}

std::vector<unsigned char> storeAsVersion(std::vector<unsigned char> bytes, uint32_t version) {
    bytes = rewriteStoreIndex(bytes, [](std::vector<unsigned char>&) {}, false);
    std::memcpy(bytes.data() + 8, &version, 4);
    if (version == 2) std::memset(bytes.data() + 108, 0, 4);
    std::memset(bytes.data() + 164, 0, kStoreHeaderBytes - 164);
    const uint32_t crc = crc32Of(bytes.data(), 160);
    std::memcpy(bytes.data() + 160, &crc, 4);
    return bytes;
}

std::vector<unsigned char> rewriteStoreIndex(std::vector<unsigned char> bytes,
                                             const std::function<void(std::vector<unsigned char>&)>& edit,
                                             bool repack) {
    uint64_t at = 0, stored = 0, raw = 0;
    std::memcpy(&at, bytes.data() + 120, 8);
    std::memcpy(&stored, bytes.data() + 128, 8);
    std::memcpy(&raw, bytes.data() + at + 8, 8);  // the packed index's raw size
    const auto unpacked = store_format::unpackIndex(bytes.data() + at, size_t(stored), raw, "test");
    std::vector<unsigned char> index(unpacked.get(), unpacked.get() + raw);
    edit(index);
    if (repack) index = store_format::packIndex(index);
    bytes.resize(size_t(at));
    bytes.insert(bytes.end(), index.begin(), index.end());
    const uint64_t size = index.size();
    std::memcpy(bytes.data() + 128, &size, 8);
    const uint32_t first = crc32Of(bytes.data(), 160);
    std::memcpy(bytes.data() + 160, &first, 4);
    const uint32_t whole = crc32Of(bytes.data(), 240);
    std::memcpy(bytes.data() + 240, &whole, 4);
    return bytes;
}

}  // namespace vdiso::test
