// vdiso serve's latency and bytes on a camera orbit (issue: remote viewing), measured with the
// C++ client over a loopback socket against a server in this process.
//
//   vdiso_serve_bench STORE.vdiso --iso V [--size 1024] [--frames 36] [--threads 1]
//                     [--cache-mb 4096] [--web DIR] [--images DIR] [--no-warmup]
//                     [--s3-endpoint URL] [--no-sign-request] [--no-full-surface]
//
// STORE may be a URL (http://, https://, s3://: the server reads it as vdiso serve would); the
// summary's full-surface and SAGE figures, which read the whole store, are then left out (as
// with --no-full-surface: a 28 GB store's full surface takes minutes).
//
// Orbit: the normal view turned 360/frames degrees a frame about the vertical axis. A first
// client runs the orbit to warm the brick cache (unless --no-warmup: then the first frame is
// as cold as the page cache), then a fresh client runs it again, measured. Prints one JSON line
// per frame (server latencies from its frameEnd, client latencies, bytes) and a summary line
// with: the full surface's bytes (its mesh through the same codec), SAGE's own output for the
// first camera (per-cell tests: what a camera-dependent chunk would send every frame), and
// with --images, the first and a later frame rendered to PNG files (bench/serve.sh
// measures them and their JPEG).
#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <string>
#include <thread>
#include <vector>

#include <nlohmann/json.hpp>

#include "cache/brick_cache.h"
#include "core/camera.h"
#include "core/extract/extract_full.h"
#include "core/extract/extract_view.h"
#include "core/view_presets.h"
#include "io/store/brick_store.h"
#include "io/json.h"
#include "io/render/png_image.h"
#include "io/render/renderer.h"
#include "serve/chunk_codec.h"
#include "serve/server.h"
#include "serve/viewer_client.h"

using namespace vdiso;
using namespace vdiso::serve;

namespace {

double median(std::vector<double> v) {
    if (v.empty()) return 0;
    std::sort(v.begin(), v.end());
    return v.size() % 2 ? v[v.size() / 2] : 0.5 * (v[v.size() / 2 - 1] + v[v.size() / 2]);
}

// What re-sending the frame whole would cost: every chunk it names, as its CHUNK message.
uint64_t wholeFrameBytes(const ViewerClient& client, const ClientFrame& f) {
    uint64_t bytes = 0;
    for (const std::vector<uint32_t>* list : {&f.chunks, &f.refs})
        for (const uint32_t b : *list) bytes += client.chunkBytes(f.store, f.iso, b);
    for (const DecodedChunk& c : f.transient)
        bytes += kChunkHeaderBytes + c.header.vertexBytes + c.header.indexBytes + c.header.pointBytes;
    return bytes;
}

}  // namespace

int main(int argc, char** argv) {
    if (argc < 2) {
        std::fprintf(stderr, "usage: vdiso_serve_bench STORE.vdiso --iso V [--size N] [--frames N] "
                             "[--threads N] [--cache-mb N] [--web DIR] [--images DIR] [--no-warmup] [--lod-error P] [--s3-endpoint URL] [--no-sign-request]\n");
        return 2;
    }
    ServeOptions options;
    options.stores = {argv[1]};
    options.port = 0;
    options.webRoot = VDISO_WEB_DIR;
    options.cacheBytes = uint64_t(4096) << 20;
    int size = 1024, frames = 36;
    bool warmup = true, fullSurface = true;
    std::string images;
    double iso = 0;
    for (int i = 2; i < argc; ++i) {
        const std::string a = argv[i];
        auto next = [&] { return std::string(i + 1 < argc ? argv[++i] : ""); };
        if (a == "--iso") iso = std::stod(next());
        else if (a == "--size") size = std::stoi(next());
        else if (a == "--frames") frames = std::stoi(next());
        else if (a == "--threads") options.threads = std::stoi(next());
        else if (a == "--cache-mb") options.cacheBytes = uint64_t(std::stoll(next())) << 20;
        else if (a == "--web") options.webRoot = next();
        else if (a == "--images") images = next();
        else if (a == "--no-warmup") warmup = false;
        else if (a == "--no-full-surface") fullSurface = false;
        else if (a == "--lod-error") options.lodError = std::stod(next());
        else if (a == "--s3-endpoint") options.remote.s3Endpoint = next();
        else if (a == "--no-sign-request") options.remote.anonymous = true;
        else {
            std::fprintf(stderr, "unknown option %s\n", a.c_str());
            return 2;
        }
    }
    options.iso = iso;
    try {
        // The bench's own view of the store (cameras, the full surface), opened first and read
        // whole, so that its reads do not share the link with the server's first frames.
        const BrickStoreReader store(argv[1], StoreOpenOptions{ReadMode::Buffered, options.remote});
        store.subBlockCodes();
        Server server(options);
        std::thread serving([&] { server.run(); });
        const VolumeInfo& volume = store.volume();
        const std::vector<Camera> orbit =
            orbitCameras(ViewPreset::Normal, volume.origin, volume.worldMax(), size, size, frames);
        auto runOrbit = [&](ViewerClient& client, bool report, uint32_t firstSeq) {
            std::vector<ClientFrame> out;
            for (int k = 0; k < frames; ++k) {
                ClientFrame f = client.requestFrame(viewMessage(orbit[size_t(k)], firstSeq + uint32_t(k), 0, iso));
                if (f.status != "complete") throw std::runtime_error("frame " + std::to_string(k) + ": " + f.frameEnd);
                if (report) {
                    const nlohmann::json end = nlohmann::json::parse(f.frameEnd);
                    JsonObject line;
                    line.add("frame", int64_t(k)).add("threads", int64_t(options.threads));
                    line.add("server_first_chunk_ms", end["firstChunkMs"].get<double>());
                    line.add("server_complete_ms", end["serverMs"].get<double>());
                    line.add("client_first_geometry_ms", f.firstGeometrySeconds * 1e3);
                    line.add("client_complete_ms", f.completeSeconds * 1e3);
                    // Levels of detail: the coarse frame that came first (-1: none).
                    line.add("client_coarse_complete_ms", f.coarseFrames ? f.coarseCompleteSeconds * 1e3 : -1.0);
                    line.add("coarse_triangles", f.coarseTriangles);
                    line.add("bytes", f.binaryBytes).add("whole_frame_bytes", wholeFrameBytes(client, f));
                    line.add("chunks", uint64_t(f.chunks.size())).add("refs", uint64_t(f.refs.size()));
                    line.add("transient_chunks", uint64_t(f.transient.size()));
                    line.add("triangles", end["triangles"].get<uint64_t>()).add("points", end["points"].get<uint64_t>());
                    line.add("bricks_read", end["bricksRead"].get<uint64_t>());
                    std::printf("%s\n", line.str().c_str());
                    std::fflush(stdout);
                }
                out.push_back(std::move(f));
            }
            return out;
        };
        if (warmup) {
            ViewerClient warm("127.0.0.1", server.port(), server.token());
            runOrbit(warm, false, 1);
        }
        ViewerClient client("127.0.0.1", server.port(), server.token());
        const std::vector<ClientFrame> measured = runOrbit(client, true, 1);

        std::vector<double> stepBytes;
        for (size_t k = 1; k < measured.size(); ++k) stepBytes.push_back(double(measured[k].binaryBytes));
        JsonObject summary;
        summary.add("summary", true).add("store", std::filesystem::path(argv[1]).filename().string());
        summary.add("iso", iso).add("size", int64_t(size)).add("threads", int64_t(options.threads));
        summary.add("first_frame_bytes", measured[0].binaryBytes);
        summary.add("median_step_bytes", median(stepBytes));
        summary.add("step_over_first", median(stepBytes) / double(std::max<uint64_t>(1, measured[0].binaryBytes)));
        const nlohmann::json firstEnd = nlohmann::json::parse(measured[0].frameEnd);
        summary.add("first_frame_triangles", firstEnd["triangles"].get<uint64_t>());
        summary.add("first_frame_points", firstEnd["points"].get<uint64_t>());
        summary.add("bytes_per_triangle_first_frame",
                    double(measured[0].binaryBytes) / double(std::max<uint64_t>(1, firstEnd["triangles"].get<uint64_t>())));
        if (!store.readsRemotely() && fullSurface) {
            // The full surface through the same codec, in one piece.
            BrickCache cache(store, options.cacheBytes);
            TriangleMesh full;
            extractOctree(cache, {iso, 4, 2}, full);
            summary.add("full_surface_triangles", uint64_t(full.triangleCount()));
            summary.add("full_surface_bytes", uint64_t(encodeChunk(ChunkHeader{}, full, PointSet{}).size()));
            // The other choice of chunk: SAGE's own output with its per-cell tests, which
            // depends on the camera and so would be sent whole every frame.
            TriangleMesh sage;
            PointSet sagePoints;
            ViewExtractOptions v = ViewExtractOptions::sage(iso);
            v.threads = options.threads;
            extractViewDependent(cache, orbit[0], v, sage, sagePoints);
            summary.add("sage_frame_triangles", uint64_t(sage.triangleCount()));
            summary.add("sage_frame_points", uint64_t(sagePoints.size()));
            summary.add("sage_frame_bytes", uint64_t(encodeChunk(ChunkHeader{}, sage, sagePoints).size()));
        }
        if (!images.empty()) {
            for (const size_t k : {size_t(0), size_t(frames / 4)}) {
                TriangleMesh mesh;
                PointSet points;
                client.assemble(measured[k], mesh, points);
                const RenderResult r = renderSurface(mesh, points, orbit[k]);
                const std::string name = images + "/frame" + std::to_string(k);
                writePng(name + ".png", r.image, true);
                // And as PPM, which cjpeg reads (for the JPEG's size).
                std::FILE* ppm = std::fopen((name + ".ppm").c_str(), "wb");
                if (!ppm) throw std::runtime_error(name + ".ppm: cannot write");
                std::fprintf(ppm, "P6\n%d %d\n255\n", r.image.width, r.image.height);
                for (size_t i = 0; i < r.image.rgba.size(); i += 4) std::fwrite(&r.image.rgba[i], 1, 3, ppm);
                std::fclose(ppm);
            }
        }
        std::printf("%s\n", summary.str().c_str());
        client.close();
        server.stop();
        serving.join();
    } catch (const std::exception& e) {
        std::fprintf(stderr, "vdiso_serve_bench: %s\n", e.what());
        return 1;
    }
    return 0;
}
