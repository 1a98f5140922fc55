// vdiso index (io/store/zarr_index.h): a Zarr array indexed where it lies opens like the store
// converted from it, brick for brick at every level (so every extraction gives the same
// triangles), for Zarr v2 and v3 and chunk shapes that are cubes, not multiples of the brick,
// and single slices; a chunk or metadata changed since indexing, another array and a damaged
// index are refused by name; and the command line indexes, describes and extracts.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>

#include "cache/brick_cache.h"
#include "core/camera.h"
#include "core/extract/extract_full.h"
#include "core/extract/extract_view.h"
#include "core/view_presets.h"
#include "io/crc32.h"
#include "io/error.h"
#include "io/readers/zarr_reader.h"
#include "io/store/brick_store.h"
#include "io/store/external_bricks.h"
#include "io/store/external_level.h"
#include "io/store/zarr_index.h"
#include "serve/protocol.h"
#include "serve/viewer_client.h"
#include "tests/loopback_servers.h"
#include "tests/mesh_test_readers.h"
#include "tests/mpi_test_util.h"
#include "tests/reader_test_util.h"
#include "tests/serve_test_util.h"
#include "tests/test_util.h"
#include "tests/zarr_test_util.h"

namespace vdiso {
namespace {

using test::expectIoError;

// A bumpy ball: its surface at 1000 crosses chunks and bricks everywhere.
double bumpyBall(int64_t x, int64_t y, int64_t z) {
    const double r = std::hypot(x - 22.3, y - 19.6, z - 18.2);
    return std::clamp(2200.0 - 70.0 * r + 180.0 * std::sin(x * 0.31) * std::cos(y * 0.27) + 140.0 * std::sin(z * 0.43),
                      0.0, 65535.0);
}

constexpr double kIso = 1000.5;

test::ArraySpec ballArray(int format, std::vector<int64_t> chunk, test::Codec codec) {
    test::ArraySpec a;
    a.format = format;
    a.dims = {45, 41, 38};
    a.chunk = std::move(chunk);
    a.codec = codec;
    a.sample = bumpyBall;
    a.extraAxes = format == 3 ? 2 : 0;
    a.separator = format == 3 ? '/' : '.';
    return a;
}

StoreWriteOptions storeOptions() {
    StoreWriteOptions o;
    o.brickSize = 8;
    return o;
}

class ZarrIndex : public test::ReaderFileTest {
protected:
    // The array written at `name`, converted into a store and indexed beside it.
    void writeAndIndex(const std::string& name, const test::ArraySpec& a) {
        test::writeArray(path(name), a);
        auto reader = openZarrVolume(path(name), 0);
        writeBrickStore(*reader, path(name + ".store"), storeOptions());
        ZarrIndexOptions o;
        o.store = storeOptions();
        const ZarrIndexSummary s = indexZarr(path(name), defaultIndexPath(path(name)), o);
        EXPECT_GT(s.chunks, 0);
        EXPECT_GT(s.dataBytes, 0u);
    }
};

TEST_F(ZarrIndex, OpensAsTheConvertedStoreBrickForBrick) {
    int n = 0;
    // Zarr v2 and v3 (format 4: v3 sharded, shards of 2 x 2 x 2 inner chunks, 1 x 2 x 2 for slices).
    for (int format : {2, 3, 4})
        for (const std::vector<int64_t>& chunk : std::vector<std::vector<int64_t>>{{16, 16, 16}, {10, 10, 10}, {1, 32, 32}}) {
            const std::string name = "a" + std::to_string(n++);
            test::ArraySpec spec = ballArray(std::min(format, 3), chunk, n % 2 ? test::Codec::Blosc : test::Codec::Zstd);
            if (format == 4) spec.shard = {chunk[0] == 1 ? 1 : 2 * chunk[0], 2 * chunk[1], 2 * chunk[2]};
            if (format == 4) spec.skip = [](int64_t x, int64_t y, int64_t z) { return x == 0 && y == 0 && z == 0; };
            writeAndIndex(name, spec);
            const std::string what = "v" + std::to_string(format) + " (4: sharded) chunks " + std::to_string(chunk[0]) + "x" +
                                     std::to_string(chunk[1]) + "x" + std::to_string(chunk[2]);
            // Opened by the data's folder (the index beside it) and by the index's path.
            const BrickStoreReader index(path(name)), byFile(path(name) + ".vdiso");
            const BrickStoreReader store(path(name + ".store"));
            ASSERT_NE(index.external(), nullptr);
            EXPECT_EQ(store.external(), nullptr);
            EXPECT_GT(index.levels().size(), 2u);
            test::expectSameStore(index, store, what);
            // No chunk read twice while it stays in the cache.
            EXPECT_EQ(index.external()->chunksRead(), uint64_t(std::ceil(45.0 / double(chunk[2])) *
                                                               std::ceil(41.0 / double(chunk[1])) *
                                                               std::ceil(38.0 / double(chunk[0]))))
                << what;
            // The same triangles, full and view-dependent (from an index that read nothing yet).
            BrickCache indexCache(byFile, 64u << 20), storeCache(store, 64u << 20);
            TriangleMesh a, b;
            extractOctree(indexCache, {kIso, 2}, a);
            extractOctree(storeCache, {kIso, 2}, b);
            EXPECT_GT(b.triangleCount(), 1000u) << what;
            test::expectSameMesh(a, b, what + " octree");
            const VolumeInfo& v = store.volume();
            const Camera camera = presetCamera(ViewPreset::Normal, v.origin, v.worldMax(), 256, 256);
            TriangleMesh va, vb;
            PointSet pa, pb;
            extractViewDependent(indexCache, camera, ViewExtractOptions::sage(kIso), va, pa);
            extractViewDependent(storeCache, camera, ViewExtractOptions::sage(kIso), vb, pb);
            EXPECT_GT(vb.triangleCount(), 100u) << what;
            test::expectSameMesh(va, vb, what + " sage");
        }
}

TEST_F(ZarrIndex, MissingChunksAreTheFillValueAndStayMissing) {
    test::ArraySpec a = ballArray(2, {16, 16, 16}, test::Codec::Gzip);
    a.fill = 5;
    a.skip = [](int64_t x, int64_t y, int64_t z) { return x == 2 && y == 0 && z == 1; };
    writeAndIndex("holes", a);
    test::expectSameStore(BrickStoreReader(path("holes")), BrickStoreReader(path("holes.store")), "holes");
    // A chunk that appears where none was is a change.
    test::ArraySpec full = a;
    full.skip = {};
    test::writeArray(path("holes"), full);
    const BrickStoreReader index(path("holes"));
    std::vector<unsigned char> brick(index.brickBytes());
    expectIoError([&] { for (int64_t id = 0; id < index.layout().brickCount(); ++id) index.readBrick(id, brick.data()); },
                  {"holes/1.0.2", "changed since it was indexed", "was missing", "vdiso index"});
}

TEST_F(ZarrIndex, ChangesSinceIndexingAreRefusedByName) {
    writeAndIndex("d", ballArray(3, {16, 16, 16}, test::Codec::Blosc));
    const std::string chunk = path("d") + "/c/0/0/1/1/2";
    ASSERT_TRUE(std::filesystem::exists(chunk));
    auto readAll = [&](const BrickStoreReader& index) {
        std::vector<unsigned char> brick(index.brickBytes());
        for (int64_t id = 0; id < index.layout().brickCount(); ++id) index.readBrick(id, brick.data());
    };
    {  // a chunk rewritten with other samples
        std::string bytes = test::readText(chunk);
        bytes[bytes.size() / 2] ^= 0x40;
        test::writeFile(chunk, bytes);
        const BrickStoreReader index(path("d"));
        expectIoError([&] { readAll(index); }, {chunk, "changed since it was indexed", "vdiso index"});
    }
    {  // a chunk gone
        std::filesystem::remove(chunk);
        const BrickStoreReader index(path("d"));
        expectIoError([&] { readAll(index); }, {chunk, "is missing"});
    }
    // Metadata changed (the fill value), another array in its place, a damaged index.
    test::ArraySpec other = ballArray(3, {16, 16, 16}, test::Codec::Blosc);
    other.fill = 3;
    test::writeArray(path("d"), other);
    expectIoError([&] { BrickStoreReader{path("d")}; }, {"d.vdiso", "metadata changed", "vdiso index"});
    other.dims = {44, 41, 38};
    std::filesystem::remove_all(path("d"));
    test::writeArray(path("d"), other);
    expectIoError([&] { BrickStoreReader{path("d")}; }, {"d.vdiso", "is not an index of", "44 x 41 x 38"});
    std::filesystem::remove_all(path("d"));
    expectIoError([&] { BrickStoreReader{path("d.vdiso")}; }, {"d.vdiso", "indexes data that cannot be opened"});
    test::writeArray(path("d"), ballArray(3, {16, 16, 16}, test::Codec::Blosc));
    ZarrIndexOptions o;
    o.store = storeOptions();
    o.store.overwrite = true;
    indexZarr(path("d"), path("d.vdiso"), o);
    const BrickStoreReader fresh(path("d"));
    readAll(fresh);
    const StoreHeader h = fresh.header();
    std::string bytes = test::readText(path("d.vdiso"));
    bytes[size_t(h.externalOffset + h.externalBytes / 2)] ^= 1;
    test::writeFile(path("d.vdiso"), bytes);
    expectIoError([&] { BrickStoreReader{path("d")}; }, {"d.vdiso", "record of the indexed data is damaged"});
    // Zarr data without an index.
    test::writeArray(path("e"), ballArray(2, {16, 16, 16}, test::Codec::Blosc));
    expectIoError([&] { BrickStoreReader{path("e")}; }, {"without an index", "vdiso index"});
}

TEST_F(ZarrIndex, FromTheCommandLine) {
    test::writeArray(path("img.zarr"), ballArray(2, {10, 10, 10}, test::Codec::Zstd));
    auto r = test::runVdiso("index " + path("img.zarr") + " --brick 8");
    ASSERT_EQ(r.exitCode, 0) << r.output;
    EXPECT_NE(r.output.find("of the data"), std::string::npos) << r.output;
    EXPECT_TRUE(std::filesystem::exists(path("img.zarr.vdiso")));
    // Not again over it without --force.
    r = test::runVdiso("index " + path("img.zarr") + " --brick 8 --quiet");
    EXPECT_NE(r.exitCode, 0) << r.output;
    r = test::runVdiso("info " + path("img.zarr"));
    ASSERT_EQ(r.exitCode, 0) << r.output;
    EXPECT_NE(r.output.find("45"), std::string::npos) << r.output;
    r = test::runVdiso("convert " + path("img.zarr") + " " + path("img.store") + " --brick 8 --quiet");
    ASSERT_EQ(r.exitCode, 0) << r.output;
    for (const char* method : {"octree", "sage"}) {
        const std::string a = path(std::string("a_") + method + ".ply"), b = path(std::string("b_") + method + ".ply");
        r = test::runVdiso("extract " + path("img.zarr") + " --iso 1000.5 --method " + method + " -o " + a);
        ASSERT_EQ(r.exitCode, 0) << r.output;
        r = test::runVdiso("extract " + path("img.store") + " --iso 1000.5 --method " + method + " -o " + b);
        ASSERT_EQ(r.exitCode, 0) << r.output;
        EXPECT_GT(test::readFile(a).size(), 10000u) << method;
        EXPECT_EQ(test::readFile(a), test::readFile(b)) << method;
    }
#ifdef VDISO_MPI_COMMAND
    // vdiso-mpi opens the folder like a store too: 3 ranks make the single process's mesh.
    r = test::runMpi(3, "extract " + path("img.zarr") + " --iso 1000.5 --method octree --quiet -o " + path("mpi.ply"));
    ASSERT_EQ(r.exitCode, 0) << r.output;
    EXPECT_EQ(test::readFile(path("mpi.ply")), test::readFile(path("b_octree.ply")));
#endif
    r = test::runVdiso("index " + path("img.zarr") + " --index http://127.0.0.1:1/x.vdiso");
    EXPECT_EQ(r.exitCode, 2) << r.output;
    r = test::runVdiso("index " + path("nothing.zarr"));
    EXPECT_NE(r.exitCode, 0);
    EXPECT_NE(r.output.find("nothing.zarr"), std::string::npos) << r.output;
}

// An index pass that stops (here, a chunk that cannot be decoded) leaves INDEX.partial and
// INDEX.resume; the next run goes on from the checkpoint and writes the very bytes of an
// uninterrupted run. A chunk the interrupted run read that changed since is refused by name;
// a checkpoint of other options is not gone on from; a damaged one is refused.
TEST_F(ZarrIndex, AnInterruptedIndexGoesOnWhereItStopped) {
    test::ArraySpec a = ballArray(2, {8, 16, 16}, test::Codec::Blosc);  // 5 layers of chunks, 5 of bricks
    test::writeArray(path("r.zarr"), a);
    ZarrIndexOptions o;
    o.store = storeOptions();
    o.checkpointSeconds = 0;  // a checkpoint at every layer of bricks
    indexZarr(path("r.zarr"), path("whole.vdiso"), o);
    const std::string whole = test::readText(path("whole.vdiso"));
    const std::string index = path("r.vdiso"), chunk = path("r.zarr/3.0.1");
    const std::string good = test::readText(chunk);
    auto interrupted = [&] {
        test::writeFile(chunk, "not blosc");
        expectIoError([&] { indexZarr(path("r.zarr"), index, o); }, {chunk});
        test::writeFile(chunk, good);
        EXPECT_FALSE(std::filesystem::exists(index));
        EXPECT_TRUE(std::filesystem::exists(indexPartialPath(index)));
        ASSERT_TRUE(std::filesystem::exists(indexCheckpointPath(index)));
    };
    // A failure before the first checkpoint leaves nothing to go on from, and no partial file.
    ZarrIndexOptions rare = o;
    rare.checkpointSeconds = 3600;
    test::writeFile(chunk, "not blosc");
    expectIoError([&] { indexZarr(path("r.zarr"), index, rare); }, {chunk});
    test::writeFile(chunk, good);
    EXPECT_FALSE(std::filesystem::exists(indexPartialPath(index)));
    EXPECT_FALSE(std::filesystem::exists(indexCheckpointPath(index)));
    interrupted();
    ZarrIndexSummary s = indexZarr(path("r.zarr"), index, o);
    EXPECT_EQ(s.store.layers, 5);
    EXPECT_EQ(s.store.resumedLayers, 1);  // layer 2 needs chunk layer 3: the last checkpoint was before layer 1
    EXPECT_TRUE(s.startedOver.empty()) << s.startedOver;
    EXPECT_EQ(s.chunks, 5 * 3 * 3);
    EXPECT_EQ(test::readText(index), whole);  // the pins of the chunks read before, the ranges, the levels
    EXPECT_FALSE(std::filesystem::exists(indexPartialPath(index)));
    EXPECT_FALSE(std::filesystem::exists(indexCheckpointPath(index)));
    test::expectSameStore(BrickStoreReader(index), BrickStoreReader(path("whole.vdiso")), "resumed");

    // The array changed between the runs: a chunk read again is refused, naming it.
    std::filesystem::remove(index);
    interrupted();
    test::ArraySpec other = a;
    other.sample = [](int64_t x, int64_t y, int64_t z) { return bumpyBall(x, y, z) + 1; };
    test::writeArray(path("r.zarr"), other);
    expectIoError([&] { indexZarr(path("r.zarr"), index, o); },
                  {"r.zarr/0.", "changed since the interrupted run", "--restart"});  // a chunk of layer 0
    ZarrIndexOptions restart = o;
    restart.restart = true;
    s = indexZarr(path("r.zarr"), index, restart);
    EXPECT_EQ(s.store.resumedLayers, 0);
    EXPECT_NE(test::readText(index), whole);

    // Other options: started over, not gone on from. A damaged checkpoint: refused.
    test::writeArray(path("r.zarr"), a);
    std::filesystem::remove(index);
    interrupted();
    ZarrIndexOptions coarser = o;
    coarser.store.brickSize = 16;
    s = indexZarr(path("r.zarr"), index, coarser);
    EXPECT_EQ(s.store.resumedLayers, 0);
    EXPECT_NE(s.startedOver.find("other options"), std::string::npos) << s.startedOver;
    EXPECT_EQ(BrickStoreReader(index).layout().brickSize, 16);
    std::filesystem::remove(index);
    interrupted();
    std::string checkpoint = test::readText(indexCheckpointPath(index));
    checkpoint[checkpoint.size() / 2] ^= 1;
    test::writeFile(indexCheckpointPath(index), checkpoint);
    expectIoError([&] { indexZarr(path("r.zarr"), index, o); }, {indexCheckpointPath(index), "damaged", "--restart"});
    s = indexZarr(path("r.zarr"), index, restart);
    EXPECT_EQ(test::readText(index), whole);

    // From the command line: the failed run says how to go on, the next one says it did.
    std::filesystem::remove(index);
    test::writeFile(chunk, "not blosc");
    auto r = test::runVdiso("index " + path("r.zarr") + " --index " + index + " --brick 8 --checkpoint-seconds 0");
    EXPECT_EQ(r.exitCode, 1) << r.output;
    EXPECT_NE(r.output.find("r.vdiso.resume keeps where the pass stood"), std::string::npos) << r.output;
    test::writeFile(chunk, good);
    r = test::runVdiso("index " + path("r.zarr") + " --index " + index + " --brick 8");
    ASSERT_EQ(r.exitCode, 0) << r.output;
    EXPECT_NE(r.output.find("went on from an interrupted run: 1 of 5 layers"), std::string::npos) << r.output;
    EXPECT_EQ(test::readText(index), whole);
}

// A record whose checksum holds but whose fields do not: refused as damaged, never trusted.
TEST(ZarrIndexRecord, InconsistentRecordsAreRefused) {
    ExternalLevel e;
    e.location = "x.zarr";
    e.chunkShape = {4, 4, 4};
    e.chunkCounts = {2, 2, 2};
    e.pins.resize(8);
    auto decode = [](const std::vector<unsigned char>& b, size_t n = 0) {
        return decodeExternalLevels(b.data(), n ? n : b.size(), "i.vdiso");
    };
    std::vector<unsigned char> good = encodeExternalLevels({e});
    ASSERT_EQ(decode(good).size(), 1u);
    EXPECT_EQ(decode(good)[0].pins.size(), 8u);
    // Two levels (an OME-Zarr's own scale as level 1): version 2, both back as written.
    ExternalLevel scale = e;
    scale.level = 1;
    scale.chunkCounts = {1, 1, 1};
    scale.pins.assign(1, ZarrChunkPin{77, 5});
    const std::vector<ExternalLevel> two = decode(encodeExternalLevels({e, scale}));
    ASSERT_EQ(two.size(), 2u);
    EXPECT_EQ(two[1].level, 1);
    EXPECT_EQ(two[1].pins[0], (ZarrChunkPin{77, 5}));
    e.pins.resize(7);  // fewer pins than chunks
    std::vector<unsigned char> bytes = encodeExternalLevels({e});
    expectIoError([&] { decode(bytes); }, {"i.vdiso", "damaged", "chunk count"});
    bytes = encodeExternalLevels({scale, e});  // the second level short of pins
    expectIoError([&] { decode(bytes); }, {"i.vdiso", "damaged", "chunk count"});
    e.pins.resize(8);
    e.chunkCounts = {int64_t(1) << 31, int64_t(1) << 31, int64_t(1) << 31};  // a product beyond 64 bits
    bytes = encodeExternalLevels({e});
    expectIoError([&] { decode(bytes); }, {"i.vdiso", "damaged"});
    e.chunkCounts = {2, 2, 2};
    e.level = -1;
    bytes = encodeExternalLevels({e});
    expectIoError([&] { decode(bytes); }, {"i.vdiso", "out of range"});
    expectIoError([&] { decode(good, 20); }, {"i.vdiso", "damaged"});
    // A level count beyond any store's, its checksum made to hold.
    e.level = 0;
    bytes = encodeExternalLevels({e, scale});
    bytes[12] = 200;
    const uint32_t crc = crc32Of(bytes.data(), bytes.size() - 4);
    std::memcpy(bytes.data() + bytes.size() - 4, &crc, 4);
    expectIoError([&] { decode(bytes); }, {"i.vdiso", "damaged", "200 levels"});
}

TEST_F(ZarrIndex, ServedLikeTheConvertedStore) {
    test::writeArray(path("img.zarr"), ballArray(3, {16, 16, 16}, test::Codec::Zstd));
    ASSERT_EQ(test::runVdiso("index " + path("img.zarr") + " --brick 8 --quiet").exitCode, 0);
    ASSERT_EQ(test::runVdiso("convert " + path("img.zarr") + " " + path("img.vdiso") + " --brick 8 --quiet").exitCode, 0);
    const std::string token = "0123456789abcdef0123";
    auto frame = [&](const std::string& store) {
        test::ServeProcess serve({store, "--port", "0", "--threads", "1", "--token", token, "--iso", "1000.5"});
        EXPECT_NE(serve.port(), 0) << "the server did not start on " << store;
        if (!serve.port()) return std::string();
        const BrickStoreReader local(path("img.vdiso"));
        const VolumeInfo& v = local.volume();
        Camera camera = presetCamera(ViewPreset::Normal, v.origin, v.worldMax(), 256, 256);
        serve::ViewerClient viewer("127.0.0.1", serve.port(), token);
        const serve::ClientFrame f = viewer.requestFrame(serve::viewMessage(camera, 1, 0, 1000.5));
        EXPECT_EQ(f.status, "complete") << f.frameEnd;
        EXPECT_GT(f.binaryBytes, 0u) << store;
        const size_t at = f.frameEnd.find("\"triangles\"");
        return at == std::string::npos ? f.frameEnd : f.frameEnd.substr(at, f.frameEnd.find_first_of(",}", at) - at);
    };
    const std::string a = frame(path("img.zarr")), b = frame(path("img.vdiso"));
    EXPECT_NE(a.find("triangles"), std::string::npos) << a;
    EXPECT_EQ(a, b);
    ASSERT_NE(a.find(':'), std::string::npos) << a;
    EXPECT_GT(std::stoull(a.substr(a.find(':') + 1)), 1000u) << a;  // a surface, not an empty frame
}

// A shard's index is checked before its offsets are used: entries outside the shard's chunk
// bytes and a CRC-32C that does not match are refused naming the shard.
TEST_F(ZarrIndex, HostileShardIndexesAreRefused) {
    EXPECT_EQ(crc32cOf("123456789", 9), 0xE3069283u);  // the check value of CRC-32C
    test::ArraySpec a = ballArray(3, {8, 8, 8}, test::Codec::Zstd);
    a.shard = {16, 16, 16};
    test::writeArray(path("sh"), a);
    const std::string shard = path("sh") + "/c/0/0/1/1/0";
    const std::string good = test::readText(shard);
    auto readAll = [&] {
        auto reader = openZarrVolume(path("sh"), 0);
        std::vector<unsigned char> slice(size_t(reader->info().sliceSamples()) * 2);
        for (int64_t z = 0; z < reader->info().dims[2]; ++z) reader->read(slice.data(), 1);
    };
    readAll();
    const size_t indexAt = good.size() - 8 * 16 - 4;
    auto withEntry = [&](size_t k, uint64_t offset, uint64_t n) {
        std::string bytes = good;
        std::memcpy(bytes.data() + indexAt + 16 * k, &offset, 8);
        std::memcpy(bytes.data() + indexAt + 16 * k + 8, &n, 8);
        const uint32_t crc = crc32cOf(bytes.data() + indexAt, 8 * 16);
        std::memcpy(bytes.data() + bytes.size() - 4, &crc, 4);
        return bytes;
    };
    test::writeFile(shard, withEntry(3, uint64_t(1) << 40, 100));
    expectIoError(readAll, {shard, "damaged shard index", "inner chunk 3"});
    test::writeFile(shard, withEntry(5, 10, good.size()));  // over the index itself
    expectIoError(readAll, {shard, "damaged shard index", "inner chunk 5"});
    std::string flipped = good;
    flipped[indexAt + 2] ^= 1;
    test::writeFile(shard, flipped);
    expectIoError(readAll, {shard, "CRC-32C"});
    test::writeFile(shard, good.substr(0, 100));
    expectIoError(readAll, {shard, "too short for its shard index"});
    test::writeFile(shard, withEntry(0, 0, 7));  // a chunk of the wrong size
    expectIoError(readAll, {shard, "inner chunk 0"});
}

// Data at a URL, its index a local file: over nginx (HTTP, Zarr v2) and the S3 server whose
// signature check is botocore's (Zarr v3, sharded), the same meshes as the converted store's; a chunk
// changed at the server is refused naming its URL.
TEST_F(ZarrIndex, DataAtAUrlIndexedIntoALocalFile) {
    test::writeArray(path("srv/bkt/v2.zarr"), ballArray(2, {16, 16, 16}, test::Codec::Blosc));
    test::ArraySpec sharded = ballArray(3, {10, 10, 10}, test::Codec::Zstd);
    sharded.shard = {20, 20, 20};  // read by ranges: the shard's index, then its inner chunks
    test::writeArray(path("srv/bkt/v3.zarr"), sharded);
    auto extract = [&](const std::string& env, const std::string& store, const std::string& out) {
        const auto r = test::runCommand(env + VDISO_BINARY + " extract '" + store + "' --iso 1000.5 --method sage -o " +
                                        path(out));
        EXPECT_EQ(r.exitCode, 0) << r.output;
        return test::readFile(path(out));
    };
    for (const char* name : {"v2", "v3"}) {
        const auto r = test::runVdiso(std::string("convert ") + path("srv/bkt/") + name + ".zarr " + path(name) +
                                      ".store --brick 8 --quiet");
        ASSERT_EQ(r.exitCode, 0) << r.output;
    }
    {
        test::LoopbackServer nginx = test::startNginx(path("srv"), path(""), path("nginx.log"));
        const std::string url = "http://127.0.0.1:" + std::to_string(nginx.port()) + "/bkt/v2.zarr";
        auto r = test::runVdiso("index " + url + " --index " + path("v2.vdiso") + " --brick 8 --quiet");
        ASSERT_EQ(r.exitCode, 0) << r.output;
        EXPECT_EQ(extract("", path("v2.vdiso"), "v2_index.ply"), extract("", path("v2.store"), "v2_store.ply"));
        r = test::runVdiso("index " + url);
        EXPECT_EQ(r.exitCode, 2) << r.output;  // a URL's index needs --index
        // Chunks read whole at their open answer from it: no disk cache of their own (each had
        // made two folders and measured the whole cache).
        r = test::runVdiso("extract " + path("v2.vdiso") + " --iso 1000.5 --method sage --disk-cache " + path("dc") +
                           " -o " + path("v2_dc.ply"));
        EXPECT_EQ(r.exitCode, 0) << r.output;
        size_t folders = 0;
        if (std::filesystem::exists(path("dc")))
            for (const auto& e : std::filesystem::recursive_directory_iterator(path("dc"))) folders += e.is_directory();
        EXPECT_EQ(folders, 0u);
        std::string chunk = test::readText(path("srv/bkt/v2.zarr/1.1.1"));
        chunk[chunk.size() / 2] ^= 0x10;
        test::writeFile(path("srv/bkt/v2.zarr/1.1.1"), chunk);
        r = test::runVdiso("extract " + path("v2.vdiso") + " --iso 1000.5 --method octree -o " + path("bad.ply"));
        EXPECT_EQ(r.exitCode, 1) << r.output;
        EXPECT_NE(r.output.find(url + "/1.1.1"), std::string::npos) << r.output;
        EXPECT_NE(r.output.find("changed since it was indexed"), std::string::npos) << r.output;
        EXPECT_FALSE(std::filesystem::exists(path("bad.ply")));
    }
    test::LoopbackServer s3 = test::startS3(path("srv"), path("s3.log"));
    const std::string env = test::s3Env(s3.port());
    const auto r = test::runCommand(env + VDISO_BINARY + " index s3://bkt/v3.zarr --index " + path("v3.vdiso") +
                                    " --brick 8 --quiet");
    ASSERT_EQ(r.exitCode, 0) << r.output;
    EXPECT_EQ(extract(env, path("v3.vdiso"), "v3_index.ply"), extract("", path("v3.store"), "v3_store.ply"));
    // Each shard opened once and its index read once; a brick's inner chunks fetched together,
    // a shard's neighbours in one range: at most a request a chunk beyond those (and the
    // metadata's few), where opening a shard for each read took 171.
    const auto stats = test::runCommand(env + VDISO_BINARY + " extract " + path("v3.vdiso") +
                                        " --iso 1000.5 --method octree --stats - --quiet");
    ASSERT_EQ(stats.exitCode, 0) << stats.output;
    auto field = [&](const std::string& name) {
        const size_t at = stats.output.find("\"" + name + "\":");
        return at == std::string::npos ? -1.0 : std::stod(stats.output.substr(at + name.size() + 3));
    };
    EXPECT_GT(field("chunks_read"), 20) << stats.output;
    const double shards = 3 * 3 * 2;  // 45 x 41 x 38 samples in shards of 20
    EXPECT_LE(field("chunk_requests"), field("chunks_read") + 2 * shards + 8) << stats.output;
    // The bucket refuses the third layer of shards' chunks: the index stops, naming the URL,
    // and the next run goes on from its checkpoint, to the uninterrupted index's bytes.
    ASSERT_TRUE(test::controlS3(s3.port(), R"({"op":"fault","action":"status","status":403,"code":"AccessDenied",)"
                                           R"("key":"/bkt/v3.zarr/c/0/0/1/*","count":-1})"));
    const std::string index = VDISO_BINARY + std::string(" index s3://bkt/v3.zarr --index ") + path("v3r.vdiso") +
                              " --brick 8 --checkpoint-seconds 0";
    auto stopped = test::runCommand(env + index);
    EXPECT_EQ(stopped.exitCode, 1) << stopped.output;
    EXPECT_NE(stopped.output.find("s3://bkt/v3.zarr/c/0/0/1/"), std::string::npos) << stopped.output;
    EXPECT_NE(stopped.output.find("v3r.vdiso.resume keeps where the pass stood"), std::string::npos) << stopped.output;
    ASSERT_TRUE(test::controlS3(s3.port(), R"({"op":"clear_faults"})"));
    const auto resumed = test::runCommand(env + index);
    ASSERT_EQ(resumed.exitCode, 0) << resumed.output;
    EXPECT_NE(resumed.output.find("went on from an interrupted run: 1 of 5 layers"), std::string::npos) << resumed.output;
    EXPECT_EQ(test::readFile(path("v3r.vdiso")), test::readFile(path("v3.vdiso")));
}

}  // namespace
}  // namespace vdiso
