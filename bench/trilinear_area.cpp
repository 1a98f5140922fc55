// How close is an extracted surface's area to the true one? The surface marching cubes
// approximates is the isosurface of the volume's trilinear interpolant; extracting from the
// volume resampled k times finer (trilinearly) converges to its area as k grows. Comparing
// k = 1 (what we extract) with the limit tells how much a triangulation over- or
// under-estimates, e.g. vdiso's fans against VTK's table (bench/log.md).
//
//   vdiso_trilinear_area VOLUME ISO K     (VOLUME: any input `vdiso convert` reads)
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <cstdio>
#include <vector>
#include <glm/geometric.hpp>
#include "cache/brick_cache.h"
#include "core/extract/extract_full.h"
#include "io/store/brick_store.h"
#include "io/store/store_writer.h"
#include "io/readers/volume_open.h"
using namespace vdiso;
struct Upsampled final : SliceReader {
    VolumeInfo in, out; const std::vector<float>& v; int k; int64_t z = 0;
    Upsampled(const VolumeInfo& i, const std::vector<float>& s, int kk) : in(i), v(s), k(kk) {
        out = i; out.type = ScalarType::F32;
        for (int a = 0; a < 3; ++a) { out.dims[a] = (i.dims[a] - 1) * k + 1; out.spacing[a] = i.spacing[a] / k; }
    }
    const VolumeInfo& info() const override { return out; }
    std::string name() const override { return "up"; }
    float at(int64_t x, int64_t y, int64_t zz) const { return v[x + in.dims[0] * (y + in.dims[1] * zz)]; }
    void read(void* dst, int64_t count) override {
        float* d = static_cast<float*>(dst);
        for (int64_t c = 0; c < count; ++c, ++z)
            for (int64_t y = 0; y < out.dims[1]; ++y)
                for (int64_t x = 0; x < out.dims[0]; ++x) {
                    double p[3] = {double(x) / k, double(y) / k, double(z) / k};
                    int64_t i0[3]; double t[3];
                    for (int a = 0; a < 3; ++a) { i0[a] = std::min<int64_t>(int64_t(p[a]), in.dims[a] - 2); t[a] = p[a] - i0[a]; }
                    double s = 0;
                    for (int cz = 0; cz < 2; ++cz) for (int cy = 0; cy < 2; ++cy) for (int cx = 0; cx < 2; ++cx)
                        s += (cx ? t[0] : 1 - t[0]) * (cy ? t[1] : 1 - t[1]) * (cz ? t[2] : 1 - t[2]) * at(i0[0] + cx, i0[1] + cy, i0[2] + cz);
                    *d++ = float(s);
                }
    }
};
int main(int argc, char** argv) {
    if (argc != 4) {
        std::fprintf(stderr, "usage: vdiso_trilinear_area VOLUME ISO K\n");
        return 2;
    }
    const std::string storePath = std::filesystem::temp_directory_path() / "vdiso_trilinear_area.vdiso";
    const double iso = std::atof(argv[2]);
    auto src = openVolume(argv[1], {});
    VolumeInfo info = src->info();
    std::vector<unsigned char> bytes(info.byteSize());
    src->read(bytes.data(), info.dims[2]);
    std::vector<float> s(info.sampleCount());
    visitScalarType(info.type, [&](auto z) { using T = decltype(z); const T* p = (const T*)bytes.data(); for (size_t i = 0; i < s.size(); ++i) s[i] = float(p[i]); });
    for (int k = 1; k <= std::atoi(argv[3]); ++k) {
        Upsampled up(info, s, k);
        StoreWriteOptions o; o.overwrite = true; o.compression = Compression::None;
        writeBrickStore(up, storePath, o);
        BrickStoreReader store(storePath);
        BrickCache cache(store, 256u << 20);
        TriangleMesh mesh;
        extractOctree(cache, {iso, 4, 2}, mesh);
        const double area = surfaceArea(mesh);
        std::printf("k=%d triangles %zu area %.1f\n", k, mesh.triangleCount(), area);
        std::fflush(stdout);
    }
    std::remove(storePath.c_str());
}
