// vdiso serve under many viewers (issue: many viewers, one server): a server in this process
// and N viewers (the C++ client of docs/protocol.md over loopback WebSockets, one thread each)
// orbiting the same store in 10-degree steps, each sending its next camera when its frame ends,
// the viewers' orbits spread around the circle. From halfway, one more viewer at a time joins
// (8 in turn, through the second half, the others orbiting on until the last has its frame)
// and asks for one view: its first coarse and final frame are timed. Prints one JSON line:
//   frame_ms_p50/p95/p99   viewers' final frames, from the VIEW to its frameEnd (client side)
//   frames_min/max         frames a viewer completed in the run; frames_per_s all of them
//   join_coarse_ms, join_final_ms   the joining viewers' first frame, median; and p95 (of 8:
//                          the second worst) join_coarse_ms_p95, join_final_ms_p95
//   threads_max            threads of the process (server and clients) sampled every 100 ms
//   server_threads_max     of them the server's: less this program's own (main, the sampler)
//                          and the clients' running at the time, until the run's end
//   peak_rss_mb            the process's peak (VmHWM): the server's, and the clients' chunk ids
//                          (they keep chunks undecoded, so that the figures are the server's:
//                          --decode to decode them too, as a browser would)
//   chunks_encoded, chunks_shared, distinct_chunks, encodings_per_chunk
//                          cacheable chunks the server encoded and sent from its shared chunks,
//                          and the distinct ones the viewers received
//
// With --followers F instead: one leader orbiting and F viewers following it (follow mode);
// prints one JSON line with the leader's frames and, for every follower's copy of a leader's
// final frame, how much later than the leader's its frameEnd arrived:
//   lag_ms_p50/p95/max, frames_followed_min/max (of leader_frames), passes_per_frame
//
//   vdiso_serve_load STORE.vdiso --iso V --viewers N [--seconds 15] [--size 1024] [--threads 2]
//                    [--cache-mb 1024] [--chunk-cache-mb 256]
//   vdiso_serve_load STORE.vdiso --iso V --followers F [--seconds 15] ...
#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <mutex>
#include <set>
#include <string>
#include <thread>
#include <vector>

#include "core/camera.h"
#include "core/view_presets.h"
#include "io/json.h"
#include "io/store/brick_store.h"
#include "serve/server.h"
#include "serve/viewer_client.h"

using namespace vdiso;
using namespace vdiso::serve;

namespace {

double percentile(std::vector<double> v, double p) {
    if (v.empty()) return 0;
    std::sort(v.begin(), v.end());
    return v[std::min(v.size() - 1, size_t(p * double(v.size() - 1) + 0.5))];
}

size_t threadCount() {
    size_t n = 0;
    for ([[maybe_unused]] const auto& entry : std::filesystem::directory_iterator("/proc/self/task")) ++n;
    return n;
}

double peakRssMb() {
    std::ifstream status("/proc/self/status");
    std::string line;
    while (std::getline(status, line))
        if (line.rfind("VmHWM:", 0) == 0) return std::stod(line.substr(6)) / 1024.0;
    return 0;
}

using Clock = std::chrono::steady_clock;

// A client thread's count among the live ones: counted by whoever starts the thread, before
// it exists; uncounted when its work ends.
struct LiveClient {
    std::atomic<int>& count;
    ~LiveClient() { --count; }
};

// One leader orbiting, `followers` following it: when each follower's copy of each of the
// leader's frames ends, against the leader's. Returns the JSON line.
std::string followRun(Server& server, const std::vector<Camera>& orbit, double iso, double seconds, int followers,
                      bool decode) {
    ViewerClient leader("127.0.0.1", server.port(), server.token());
    leader.setDecode(decode);
    std::vector<std::unique_ptr<ViewerClient>> clients;
    for (int k = 0; k < followers; ++k)
        clients.push_back(std::make_unique<ViewerClient>("127.0.0.1", server.port(), server.token(),
                                                         "follow=" + leader.session()));
    for (auto& client : clients) client->setDecode(decode);
    std::mutex mutex;
    std::vector<std::map<uint32_t, Clock::time_point>> seen{size_t(followers)};
    std::vector<std::thread> threads;
    for (int k = 0; k < followers; ++k)
        threads.emplace_back([&, k] {
            try {  // until the server stops and closes the connection
                while (true) {
                    const ClientFrame f = clients[size_t(k)]->readFollowedFrame();
                    const Clock::time_point at = Clock::now();
                    std::lock_guard lock(mutex);
                    if (f.status == "complete") seen[size_t(k)][f.frame] = at;
                }
            } catch (const std::exception&) {
            }
        });
    std::map<uint32_t, Clock::time_point> led;
    const uint64_t passesBefore = server.counters().framePasses;
    const auto deadline = Clock::now() + std::chrono::duration<double>(seconds);
    for (uint32_t seq = 1; Clock::now() < deadline; ++seq) {
        const ClientFrame f = leader.requestFrame(viewMessage(orbit[seq % orbit.size()], seq, 0, iso));
        if (f.status == "complete") led[seq] = Clock::now();
    }
    const uint64_t passes = server.counters().framePasses - passesBefore;
    std::this_thread::sleep_for(std::chrono::milliseconds(500));  // the last copies arrive
    for (auto& client : clients) client->interrupt();
    for (std::thread& t : threads) t.join();
    leader.close();  // while the server still answers
    server.stop();
    std::vector<double> lags;
    int fewest = int(led.size()), most = 0;
    for (const auto& copies : seen) {
        int followed = 0;
        for (const auto& [frame, at] : led) {
            const auto copy = copies.find(frame);
            if (copy == copies.end()) continue;
            ++followed;
            lags.push_back(std::chrono::duration<double, std::milli>(copy->second - at).count());
        }
        fewest = std::min(fewest, followed);
        most = std::max(most, followed);
    }
    JsonObject line;
    line.add("followers", int64_t(followers)).add("leader_frames", uint64_t(led.size()));
    line.add("passes_per_frame", led.empty() ? 0.0 : double(passes) / double(led.size()));
    line.add("frames_followed_min", int64_t(fewest)).add("frames_followed_max", int64_t(most));
    line.add("lag_ms_p50", percentile(lags, 0.5)).add("lag_ms_p95", percentile(lags, 0.95));
    line.add("lag_ms_max", lags.empty() ? 0.0 : *std::max_element(lags.begin(), lags.end()));
    return line.str();
}

}  // namespace

int main(int argc, char** argv) {
    if (argc < 2) {
        std::fprintf(stderr, "usage: vdiso_serve_load STORE.vdiso --iso V --viewers N [--seconds S] [--size PX]\n"
                             "       [--threads N] [--cache-mb N] [--chunk-cache-mb N] [--followers F] [--decode]\n");
        return 2;
    }
    ServeOptions options;
    options.stores = {argv[1]};
    options.port = 0;
    options.threads = 2;
    options.webRoot = VDISO_WEB_DIR;
    options.maxViewers = 1000;
    double iso = 0, seconds = 15;
    int viewers = 1, size = 1024, followers = 0;
    bool decode = false;
    for (int i = 2; i < argc; ++i) {
        const std::string a = argv[i];
        auto next = [&] { return std::string(i + 1 < argc ? argv[++i] : ""); };
        if (a == "--iso") iso = std::stod(next());
        else if (a == "--viewers") viewers = std::stoi(next());
        else if (a == "--followers") followers = std::stoi(next());
        else if (a == "--decode") decode = true;
        else if (a == "--seconds") seconds = std::stod(next());
        else if (a == "--size") size = std::stoi(next());
        else if (a == "--threads") options.threads = std::stoi(next());
        else if (a == "--cache-mb") options.cacheBytes = uint64_t(std::stoll(next())) << 20;
        else if (a == "--chunk-cache-mb") options.chunkCacheBytes = uint64_t(std::stoll(next())) << 20;
        else {
            std::fprintf(stderr, "unknown option %s\n", a.c_str());
            return 2;
        }
    }
    options.iso = iso;
    try {
        std::vector<Camera> orbit;
        {
            const BrickStoreReader store(argv[1]);
            const VolumeInfo& v = store.volume();
            orbit = orbitCameras(ViewPreset::Normal, v.origin, v.worldMax(), size, size, 36);
        }
        Server server(options);
        std::thread serving([&] { server.run(); });
        if (followers > 0) {
            const std::string line = followRun(server, orbit, iso, seconds, followers, decode);
            serving.join();
            std::printf("{\"store\": %s, %s\n", jsonQuote(std::filesystem::path(argv[1]).filename().string()).c_str(),
                        line.c_str() + 1);
            return 0;
        }
        const auto start = std::chrono::steady_clock::now();
        const auto deadline = start + std::chrono::duration<double>(seconds);

        std::mutex mutex;  // guards the results below
        std::vector<double> frameMs;
        std::vector<int> framesOf(size_t(viewers), 0);
        std::set<uint32_t> distinct;
        std::vector<std::string> failures;
        std::atomic<size_t> threadsMax{0}, serverThreadsMax{0};
        std::atomic<int> liveClients{0};
        std::atomic<bool> done{false}, joined{false};
        std::thread sampler([&] {
            while (!done) {
                // Counted before the clients: a client counts as live before its thread exists.
                const size_t all = threadCount();
                const int live = liveClients.load();
                threadsMax = std::max(threadsMax.load(), all);
                // Until the deadline: after it, clients' threads end after they say so.
                if (std::chrono::steady_clock::now() < deadline)
                    serverThreadsMax = std::max(serverThreadsMax.load(), all - size_t(std::max(0, live)) - 2);
                std::this_thread::sleep_for(std::chrono::milliseconds(100));
            }
        });
        std::vector<std::thread> clients;
        for (int k = 0; k < viewers; ++k) {
            ++liveClients;  // before its thread exists: never counted as the server's
            clients.emplace_back([&, k] {
                const LiveClient live{liveClients};
                try {
                    ViewerClient client("127.0.0.1", server.port(), server.token());
                    client.setDecode(decode);
                    const size_t first = size_t(k) * orbit.size() / size_t(viewers);
                    // Until the deadline, and on while viewers still join (so that they join a busy server).
                    for (uint32_t seq = 1; std::chrono::steady_clock::now() < deadline || !joined; ++seq) {
                        const ClientFrame f =
                            client.requestFrame(viewMessage(orbit[(first + seq) % orbit.size()], seq, 0, iso));
                        std::lock_guard lock(mutex);
                        if (f.status != "complete") continue;
                        frameMs.push_back(f.completeSeconds * 1e3);
                        ++framesOf[size_t(k)];
                        distinct.insert(f.chunks.begin(), f.chunks.end());
                    }
                } catch (const std::exception& e) {
                    std::lock_guard lock(mutex);
                    failures.push_back(e.what());
                }
            });
        }
        // The joining viewers, one at a time through the second half, each on a thread of its
        // own (a slow final frame does not put off the next one's joining).
        constexpr int kJoins = 8;
        std::vector<double> joinCoarse, joinFinal;
        std::vector<std::thread> joiners;
        for (int j = 0; j < kJoins; ++j) {
            std::this_thread::sleep_until(start + std::chrono::duration<double>(seconds * (0.5 + 0.45 * j / kJoins)));
            ++liveClients;
            joiners.emplace_back([&, j] {
                const LiveClient live{liveClients};
                try {
                    ViewerClient joining("127.0.0.1", server.port(), server.token());
                    joining.setDecode(decode);
                    const ClientFrame f =
                        joining.requestFrame(viewMessage(orbit[size_t(5 * j) % orbit.size()], 1, 0, iso));
                    std::lock_guard lock(mutex);
                    joinCoarse.push_back(f.coarseFrames ? f.coarseCompleteSeconds * 1e3 : -1);
                    joinFinal.push_back(f.completeSeconds * 1e3);
                } catch (const std::exception& e) {
                    std::lock_guard lock(mutex);
                    failures.push_back(e.what());
                }
            });
        }
        for (std::thread& t : joiners) t.join();
        joined = true;
        for (std::thread& t : clients) t.join();
        done = true;
        sampler.join();
        const ServerCounters counters = server.counters();
        server.stop();
        serving.join();
        const double elapsed = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();

        JsonObject line;
        line.add("store", std::filesystem::path(argv[1]).filename().string()).add("viewers", int64_t(viewers));
        line.add("threads_per_frame", int64_t(options.threads)).add("seconds", elapsed);
        line.add("chunk_cache_mb", int64_t(options.chunkCacheBytes >> 20));
        line.add("frames", uint64_t(frameMs.size())).add("frames_per_s", double(frameMs.size()) / elapsed);
        line.add("frame_ms_p50", percentile(frameMs, 0.5)).add("frame_ms_p95", percentile(frameMs, 0.95));
        line.add("frame_ms_p99", percentile(frameMs, 0.99));
        line.add("frames_min", int64_t(*std::min_element(framesOf.begin(), framesOf.end())));
        line.add("frames_max", int64_t(*std::max_element(framesOf.begin(), framesOf.end())));
        line.add("join_coarse_ms", percentile(joinCoarse, 0.5)).add("join_final_ms", percentile(joinFinal, 0.5));
        line.add("join_coarse_ms_p95", percentile(joinCoarse, 0.95)).add("join_final_ms_p95", percentile(joinFinal, 0.95));
        line.add("threads_max", uint64_t(threadsMax.load())).add("server_threads_max", uint64_t(serverThreadsMax.load()));
        line.add("peak_rss_mb", peakRssMb());
        line.add("chunks_encoded", counters.chunksEncoded).add("chunks_shared", counters.chunksShared);
        line.add("distinct_chunks", uint64_t(distinct.size()));
        line.add("encodings_per_chunk", distinct.empty() ? 0.0 : double(counters.chunksEncoded) / double(distinct.size()));
        line.add("viewer_failures", uint64_t(failures.size()));
        std::printf("%s\n", line.str().c_str());
        for (const std::string& f : failures) std::fprintf(stderr, "vdiso_serve_load: a viewer failed: %s\n", f.c_str());
        return failures.empty() ? 0 : 1;
    } catch (const std::exception& e) {
        std::fprintf(stderr, "vdiso_serve_load: %s\n", e.what());
        return 1;
    }
}
