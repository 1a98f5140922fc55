// Brick stores: the input is a store file whose checksums (header (both), index, each brick) are
// recomputed here, so mutations reach the checks behind them: field validation, index
// entries, brick decoding, and, for small volumes, extraction on hostile ranges and samples, at
// every level of detail the store holds.
#include <cstring>
#include <vector>

#include "cache/brick_cache.h"
#include "core/camera.h"
#include "core/extract/extract_full.h"
#include "core/extract/extract_view.h"
#include "core/lod/level_source.h"
#include "core/orientation.h"
#include "core/view_presets.h"
#include "fuzz/fuzz_input.h"
#include "io/crc32.h"
#include "io/store/brick_store.h"
#include "io/store/store_format.h"

namespace {

template <class T>
T load(const std::vector<uint8_t>& b, uint64_t at) {
    T v;
    std::memcpy(&v, b.data() + at, sizeof v);
    return v;
}

template <class T>
void store(std::vector<uint8_t>& b, uint64_t at, T v) {
    std::memcpy(b.data() + at, &v, sizeof v);
}

// The checksums a writer would have made for these bytes.
void fixChecksums(std::vector<uint8_t>& b) {
    if (b.size() < vdiso::kStoreHeaderBytes) return;
    const uint64_t indexOffset = load<uint64_t>(b, 120), indexSize = load<uint64_t>(b, 128);
    if (indexOffset < b.size() && indexSize >= 20 && indexSize <= b.size() - indexOffset) {
        const uint64_t count = load<uint64_t>(b, indexOffset + 8);
        for (uint64_t i = 0; i < count && 16 + 32 * (i + 1) <= indexSize - 4; ++i) {
            const uint64_t entry = indexOffset + 16 + 32 * i;
            const uint64_t offset = load<uint64_t>(b, entry);
            const uint32_t stored = load<uint32_t>(b, entry + 8);
            if (offset < b.size() && stored <= b.size() - offset)
                store(b, entry + 12, vdiso::crc32Of(b.data() + offset, stored));
        }
        store(b, indexOffset + indexSize - 4, vdiso::crc32Of(b.data() + indexOffset, indexSize - 4));
    }
    store(b, 160, vdiso::crc32Of(b.data(), 160));
    // Version 4's second checksum, over the orientation too (older versions ignore the bytes).
    store(b, 240, vdiso::crc32Of(b.data(), 240));
}

void exercise(const std::string& path) {
    const vdiso::BrickStoreReader reader(path);
    const int64_t bricks = int64_t(reader.index().size());  // every level's
    if (reader.brickBytes() > (size_t(16) << 20)) return;
    std::vector<unsigned char> samples(reader.brickBytes());
    for (int64_t id = 0; id < bricks && id < 64; ++id) reader.readBrick(id, samples.data());
    if (bricks > 64) return;
    // Small enough to extract: the full surface and one view, at the middle of the range.
    vdiso::BrickCache cache(reader, uint64_t(bricks + 2) * reader.brickBytes());
    const double iso = 0.5 * (reader.header().valueMin + reader.header().valueMax);
    vdiso::TriangleMesh mesh;
    vdiso::extractOctree(cache, {iso, 4}, mesh);
    // Two threads count, then write in place: bricks that disagree on what they share, or
    // ranges that lie, must not break the placeholders' resolution.
    vdiso::TriangleMesh placed;
    vdiso::extractOctree(cache, {iso, 4, 2}, placed);
    if (placed.triangleCount() != mesh.triangleCount()) __builtin_trap();
    const vdiso::VolumeInfo& v = reader.volume();
    // As vdiso extract writes it: in physical space, and seen from the patient's front.
    vdiso::transformMesh(vdiso::volumeToPhysical(v), mesh);
    const vdiso::Camera camera = vdiso::presetCamera(vdiso::ViewPreset::Normal, vdiso::viewFacing(std::nullopt, v),
                                                     v.origin, v.worldMax(), 64, 64);
    vdiso::TriangleMesh visible;
    vdiso::PointSet points;
    vdiso::extractViewDependent(cache, camera, vdiso::ViewExtractOptions::sage(iso), visible, points);
    if (reader.levels().size() < 2) return;
    // The coarsest level whole, and a view choosing its levels (cells up to 8 pixels).
    vdiso::LevelSource coarsest(cache, int(reader.levels().size()) - 1);
    vdiso::TriangleMesh coarse;
    vdiso::extractOctree(coarsest, {iso, 4}, coarse);
    vdiso::ViewExtractOptions lod = vdiso::ViewExtractOptions::sage(iso);
    lod.lodError = 8;
    vdiso::TriangleMesh levels;
    vdiso::PointSet levelPoints;
    vdiso::extractViewDependent(cache, camera, lod, levels, levelPoints);
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    std::vector<uint8_t> bytes(data, data + size);
    fixChecksums(bytes);
    vdiso::fuzz::MemoryFile file(bytes.data(), bytes.size());
    vdiso::fuzz::expectAnswer([&] { exercise(file.path()); });
    return 0;
}
