// Stores at URLs against servers that misbehave on purpose (tests/remote/s3_server.py's faults):
// credentials never follow a redirect to another place; every answer's version is checked; a
// Retry-After is honoured within the read's budget; a small object sent whole by a server that
// ignores ranges is taken; huge headers and encoded bodies are named as what they are; a server
// that drips bytes meets the read's deadline; the disk cache keeps only ranges whose checksum
// passed; and `vdiso serve` on a dripping store ends frames with an error and stops on Ctrl-C.
#include <gtest/gtest.h>

#include <chrono>
#include <csignal>
#include <future>
#include <thread>
#include <string>
#include <vector>

#include <sys/wait.h>
#include <unistd.h>

#include <nlohmann/json.hpp>

#include "core/camera.h"
#include "core/interrupt.h"
#include "core/view_presets.h"
#include "io/crc32.h"
#include "io/error.h"
#include "io/remote/http_answer.h"
#include "io/remote/remote_file.h"
#include "io/store/brick_store.h"
#include "io/store/store_format.h"
#include "serve/protocol.h"
#include "serve/server.h"
#include "serve/viewer_client.h"
#include "tests/loopback_servers.h"
#include "tests/serve_test_util.h"
#include "tests/test_util.h"

namespace vdiso {
namespace {

using test::LoopbackServer;
using Clock = std::chrono::steady_clock;

double secondsSince(Clock::time_point start) { return std::chrono::duration<double>(Clock::now() - start).count(); }

class RemoteHostile : public ::testing::Test {
protected:
    void SetUp() override {
        std::filesystem::create_directories(mDir.path() / "bkt");
        const test::CommandResult r = test::runVdiso("synth " + file("bkt/head.vdiso") + " --kind head --size 96 --quiet");
        ASSERT_EQ(r.exitCode, 0) << r.output;
    }
    std::string file(const std::string& name) const { return mDir.file(name); }
    LoopbackServer s3(const std::vector<std::string>& extra = {}) {
        return test::startS3(mDir.path().string(), file("s3.log"), extra);
    }
    static void control(int port, const std::string& json) { ASSERT_TRUE(test::controlS3(port, json)); }
    // Reading the S3 test server's public bucket at `port` without credentials.
    static RemoteOptions publicBucket(int port) {
        RemoteOptions options;
        options.s3Endpoint = "http://127.0.0.1:" + std::to_string(port);
        options.anonymous = true;
        return options;
    }
    // The server's count of requests so far.
    static int64_t requestsTo(int port) {
        const test::CommandResult r =
            test::runCommand("curl -sf 'http://127.0.0.1:" + std::to_string(port) + "/__stats?log=0'");
        return nlohmann::json::parse(r.output)["total"]["requests"].get<int64_t>();
    }
    test::CommandResult extract(const std::string& prefix, const std::string& location, const std::string& name,
                                const std::string& extra = "") {
        return test::runCommand(prefix + VDISO_BINARY + " extract '" + location +
                                "' --iso 600.5 --method sage --size 256x256 --png " + file(name + ".png") +
                                " --force " + extra);
    }
    static void expectError(const test::CommandResult& r, std::initializer_list<std::string> parts) {
        EXPECT_EQ(r.exitCode, 1) << r.output;
        for (const std::string& p : parts) EXPECT_NE(r.output.find(p), std::string::npos) << p << " not in: " << r.output;
    }

    test::ScratchDir mDir;
};

// A signed request redirected to another port (the same host) or host: refused, naming both
// places, and the other place never hears of it (not the session token, not anything). The
// same redirect of an anonymous request is followed; a signed one within its endpoint too.
TEST_F(RemoteHostile, CredentialsNeverFollowARedirectElsewhere) {
    LoopbackServer signedServer = s3({"--public", "bkt"});  // signed requests are checked all the same
    LoopbackServer elsewhere = s3({"--public", "bkt"});
    const int port = signedServer.port(), other = elsewhere.port();
    const std::string env = test::s3Env(port);
    for (const char* status : {"301", "302", "307"}) {
        for (const std::string& target : {"http://127.0.0.1:" + std::to_string(other) + "/bkt/head.vdiso",
                                          "http://localhost:" + std::to_string(port) + "/bkt/head.vdiso"}) {
            SCOPED_TRACE(std::string(status) + " to " + target);
            control(port, std::string(R"([{"op":"clear_faults"},{"op":"fault","action":"redirect","status":)") +
                              status + R"(,"count":-1,"location":")" + target + R"("}])");
            const test::CommandResult r = test::runCommand(env + VDISO_BINARY + " info s3://bkt/head.vdiso");
            expectError(r, {"s3://bkt/head.vdiso", "was redirected (HTTP " + std::string(status) + ")",
                            "127.0.0.1:" + std::to_string(port), target, "not followed"});
        }
    }
    EXPECT_EQ(requestsTo(other), 0) << "a signed request reached the redirect's target";
    // Anonymous: nothing to leak, the redirect is followed and the other server answers.
    control(port, std::string(R"([{"op":"clear_faults"},{"op":"fault","action":"redirect","status":307,"count":-1,)") +
                      R"("location":"http://127.0.0.1:)" + std::to_string(other) + R"(/bkt/head.vdiso"}])");
    const test::CommandResult anonymous = test::runCommand(
        std::string(VDISO_BINARY) + " info s3://bkt/head.vdiso --no-sign-request --s3-endpoint http://127.0.0.1:" +
        std::to_string(port));
    EXPECT_EQ(anonymous.exitCode, 0) << anonymous.output;
    EXPECT_GT(requestsTo(other), 0);
    // Signed, redirected within its own endpoint (the same URL, twice): followed and signed anew.
    control(port, R"([{"op":"clear_faults"},{"op":"fault","action":"redirect","status":307,"count":2}])");
    const test::CommandResult within = test::runCommand(env + VDISO_BINARY + " info s3://bkt/head.vdiso");
    EXPECT_EQ(within.exitCode, 0) << within.output;
}

// A permanent redirect (301, 308) is remembered: after the first answer from where it leads,
// the object's reads go straight there. A temporary one (302, 307) is followed at every read.
TEST_F(RemoteHostile, APermanentRedirectIsFollowedOnceATemporaryOneEveryTime) {
    LoopbackServer first = s3({"--public", "bkt"});
    LoopbackServer second = s3({"--public", "bkt"});
    const int port = first.port(), other = second.port();
    for (const char* status : {"301", "308", "307"}) {
        SCOPED_TRACE(status);
        control(port, std::string(R"([{"op":"clear_faults"},{"op":"fault","action":"redirect","status":)") + status +
                          R"(,"count":-1,"location":"http://127.0.0.1:)" + std::to_string(other) +
                          R"(/bkt/head.vdiso"}])");
        const int64_t firstBefore = requestsTo(port), secondBefore = requestsTo(other);
        const test::CommandResult r = extract("", "s3://bkt/head.vdiso", std::string("moved") + status,
                                              "--no-sign-request --s3-endpoint http://127.0.0.1:" + std::to_string(port));
        ASSERT_EQ(r.exitCode, 0) << r.output;
        const int64_t toFirst = requestsTo(port) - firstBefore, toSecond = requestsTo(other) - secondBefore;
        EXPECT_GT(toSecond, 5);
        if (std::string(status) == "307") EXPECT_EQ(toFirst, toSecond) << "each read is redirected";
        else EXPECT_EQ(toFirst, 1) << "only the first read is redirected (" << toSecond << " reads went on)";
    }
}

// Answers that are not what was asked: each is an error that says what it is.
TEST_F(RemoteHostile, AnswersAreCheckedAndNamed) {
    LoopbackServer server = s3();
    const int port = server.port();
    const std::string env = test::s3Env(port);
    struct Case {
        const char* fault;
        std::vector<std::string> parts;
    };
    const Case cases[] = {
        // A server that ignores If-Match and sends another version's bytes.
        {R"({"op":"fault","action":"replaced","count":-1,"skip":1})",
         {"was replaced since it was opened", "replaced-version"}},
        {R"({"op":"fault","action":"none","headers":{"Content-Encoding":"gzip"},"count":-1,"skip":1})",
         {"Content-Encoding 'gzip'", "was not asked for"}},
        {R"({"op":"fault","action":"none","header_bytes":10000000,"count":-1})", {"more than 64 KiB of headers"}},
        // The server's wait, beyond what the read may take: not waited for.
        {R"({"op":"fault","action":"status","status":503,"headers":{"Retry-After":"120"},"count":-1,"skip":1})",
         {"HTTP 503", "Retry-After: 120", "--remote-deadline"}},
        // A refusal names the range it refused.
        {R"({"op":"fault","action":"status","status":403,"count":-1,"skip":1})", {"HTTP 403", "for range "}},
    };
    for (const Case& c : cases) {
        SCOPED_TRACE(c.fault);
        control(port, std::string("[{\"op\":\"clear_faults\"},") + c.fault + "]");
        std::filesystem::remove(file("bad.png"));
        const Clock::time_point start = Clock::now();
        const test::CommandResult r = extract("timeout 60 " + env, "s3://bkt/head.vdiso", "bad", "--remote-deadline 30");
        expectError(r, {"s3://bkt/head.vdiso"});
        for (const std::string& p : c.parts) EXPECT_NE(r.output.find(p), std::string::npos) << p << ": " << r.output;
        EXPECT_EQ(r.output.find("Out of memory"), std::string::npos) << r.output;
        EXPECT_LT(secondsSince(start), 20.0) << r.output;
        EXPECT_FALSE(std::filesystem::exists(file("bad.png")));
    }
    // A Retry-After within the budget is waited for: 503s asking 1 s, then answers.
    control(port, R"([{"op":"clear_faults"},{"op":"fault","action":"status","status":503,)"
                  R"("headers":{"Retry-After":"1"},"count":2,"skip":3}])");
    const Clock::time_point start = Clock::now();
    const test::CommandResult r = extract(env, "s3://bkt/head.vdiso", "waited");
    EXPECT_EQ(r.exitCode, 0) << r.output;
    EXPECT_GE(secondsSince(start), 1.0) << "Retry-After was not waited for";
}

// A server that ignores ranges: a small object it sends whole is taken (a Zarr's metadata and
// chunks are read whole anyway); a store, read by ranges, is refused.
TEST_F(RemoteHostile, ASmallObjectSentWholeIsTaken) {
    LoopbackServer server = s3({"--public", "bkt"});
    const int port = server.port();
    const std::string text = R"({"zarr_format": 2, "note": "read whole"})";
    test::writeFile(file("bkt/small.json"), text);
    control(port, R"([{"op":"fault","action":"ignore_range","count":-1}])");
    const RemoteOptions options = publicBucket(port);
    const RemoteFile small("s3://bkt/small.json", options, 4096);
    ASSERT_EQ(small.size(), text.size());
    std::string got(text.size(), '\0');
    small.read(0, got.size(), got.data());
    EXPECT_EQ(got, text);
    try {
        RemoteFile large("s3://bkt/head.vdiso", options, 4096);
        ADD_FAILURE() << "a store served without ranges was opened";
    } catch (const IoError& e) {
        EXPECT_NE(std::string(e.what()).find("without byte ranges"), std::string::npos) << e.what();
    }
}

// A server that sends a byte every half second never trips the stall timeout: the read's
// deadline ends it, with a message naming it (`info` waited about 4,096 s for a header).
TEST_F(RemoteHostile, ADrippingServerMeetsTheDeadline) {
    LoopbackServer server = s3();
    const int port = server.port();
    control(port, R"([{"op":"fault","action":"throttle","bps":2,"count":-1}])");
    const Clock::time_point start = Clock::now();
    const test::CommandResult r = test::runCommand("timeout 60 " + test::s3Env(port) + VDISO_BINARY +
                                                   " info s3://bkt/head.vdiso --remote-deadline 2");
    expectError(r, {"s3://bkt/head.vdiso", "within 2 s (--remote-deadline)"});
    EXPECT_LT(secondsSince(start), 15.0) << r.output;
}

// A brick that arrives corrupt once is not kept in the disk cache: the run fails, the next one
// (the server healed) succeeds. An entry kept damaged (right length and entry CRC, wrong bytes:
// as an older vdiso kept what arrived) is dropped and fetched again, and then kept right.
TEST_F(RemoteHostile, TheDiskCacheKeepsOnlyVerifiedRanges) {
    LoopbackServer server = s3();
    const int port = server.port();
    const std::string env = test::s3Env(port), cache = "--disk-cache " + file("cache");
    ASSERT_EQ(extract("", file("bkt/head.vdiso"), "local").exitCode, 0);
    // Every answer after the open's and the index's arrives corrupt, once each.
    control(port, R"([{"op":"fault","action":"corrupt","count":-1,"skip":3}])");
    expectError(extract(env, "s3://bkt/head.vdiso", "poisoned", cache), {"checksum mismatch"});
    control(port, R"([{"op":"clear_faults"}])");
    const test::CommandResult healed = extract(env, "s3://bkt/head.vdiso", "healed", cache);
    ASSERT_EQ(healed.exitCode, 0) << healed.output;
    EXPECT_EQ(test::readFile(file("healed.png")), test::readFile(file("local.png")));

    // Damage kept entries behind their own CRC.
    std::vector<std::string> entries;
    for (const auto& e : std::filesystem::recursive_directory_iterator(file("cache")))
        if (e.is_regular_file()) entries.push_back(e.path().string());
    ASSERT_GT(entries.size(), 4u);
    std::vector<std::vector<unsigned char>> planted;
    for (const std::string& path : entries) {
        std::vector<unsigned char> bytes = test::readFile(path);
        const size_t n = bytes.size() - 4;
        bytes[n / 2] ^= 0x5a;
        const uint32_t crc = crc32Of(bytes.data(), n);
        std::memcpy(bytes.data() + n, &crc, 4);
        test::writeFile(path, bytes.data(), bytes.size());
        planted.push_back(bytes);
    }
    const test::CommandResult again = extract(env, "s3://bkt/head.vdiso", "again", cache);
    ASSERT_EQ(again.exitCode, 0) << again.output;
    EXPECT_EQ(test::readFile(file("again.png")), test::readFile(file("local.png")));
    size_t mended = 0;
    for (size_t k = 0; k < entries.size(); ++k)
        mended += std::filesystem::exists(entries[k]) && test::readFile(entries[k]) != planted[k];
    EXPECT_GT(mended, 0u) << "no damaged entry was fetched again and kept right";
}

// Only a range whose check passed is kept in the disk cache: one read without a check is not
// (the raw index of a store before version 5 and an index's record of its data were read so,
// and one that arrived corrupt was served from the cache on every later run). The raw index is
// now read with its CRC as the check: a store of version 3 through the cache.
TEST_F(RemoteHostile, ARangeReadWithoutACheckIsNotKept) {
    LoopbackServer server = s3({"--public", "bkt"});
    const int port = server.port();
    RemoteOptions options = publicBucket(port);
    options.diskCacheDir = file("cache");
    auto entries = [&] {
        size_t n = 0;
        for (const auto& e : std::filesystem::recursive_directory_iterator(file("cache"))) n += e.is_regular_file();
        return n;
    };
    std::vector<unsigned char> got(10000);
    {
        const RemoteFile store("s3://bkt/head.vdiso", options, 4096);
        store.read(100000, got.size(), got.data());                                   // unchecked
        store.read(200000, got.size(), got.data(), [](size_t) { return true; });     // checked, passes
        store.read(300000, got.size(), got.data(), [](size_t) { return false; });    // checked, fails
    }  // the cache's writes are made here
    EXPECT_EQ(entries(), 1u);

    const std::vector<unsigned char> v3 = test::storeAsVersion(test::readFile(file("bkt/head.vdiso")), 3);
    test::writeFile(file("bkt/v3.vdiso"), v3.data(), v3.size());
    const std::string env = test::s3Env(port), cache = "--disk-cache " + file("cache3");
    ASSERT_EQ(extract("", file("bkt/v3.vdiso"), "local3").exitCode, 0);
    for (const char* name : {"filled3", "cached3"}) {
        const test::CommandResult r =
            extract(env, "s3://bkt/v3.vdiso", name, cache + " --stats " + file(std::string(name) + ".json"));
        ASSERT_EQ(r.exitCode, 0) << r.output;
        EXPECT_EQ(test::readFile(file(std::string(name) + ".png")), test::readFile(file("local3.png")));
    }
    const std::string stats = test::readText(file("cached3.json"));
    EXPECT_NE(stats.find("\"disk_cache_hits\": "), std::string::npos) << stats;
    EXPECT_EQ(stats.find("\"disk_cache_hits\": 0,"), std::string::npos) << "the index and bricks came from the cache: " << stats;
}

// A server that turns slow after the session has learnt its usual wait: each read is ended as a
// straggler once, then waits for its answer (it was ended at every try and the run failed with
// its attempts used up), and the run gives the local picture.
TEST_F(RemoteHostile, AServerThatTurnsSlowIsWaitedFor) {
    LoopbackServer server = s3();
    const int port = server.port();
    ASSERT_EQ(extract("", file("bkt/head.vdiso"), "local").exitCode, 0);
    control(port, R"([{"op":"fault","action":"delay","ms":1500,"count":-1,"skip":12}])");
    const test::CommandResult r = extract(test::s3Env(port), "s3://bkt/head.vdiso", "slow", "--stats " + file("slow.json"));
    ASSERT_EQ(r.exitCode, 0) << r.output;
    EXPECT_EQ(test::readFile(file("slow.png")), test::readFile(file("local.png")));
    EXPECT_EQ(test::readText(file("slow.json")).find("\"remote_stragglers\": 0,"), std::string::npos)
        << "no read was ended as a straggler: the test did not reach what it tests";
}

// A read that fails for good ends the object's other reads in flight (their frame is lost),
// unless it was read alone (the index's parts read in the background): a 403 on one of those
// had ended a frame's brick reads.
TEST_F(RemoteHostile, AReadThatFailsAloneEndsNoOtherRead) {
    LoopbackServer server = s3({"--public", "bkt"});
    const int port = server.port();
    const RemoteOptions options = publicBucket(port);
    const RemoteFile store("s3://bkt/head.vdiso", options, 4096);
    for (const bool alone : {true, false}) {
        SCOPED_TRACE(alone ? "alone" : "a frame's");
        // The next request waits 600 ms; every one after it is refused.
        control(port, R"([{"op":"clear_faults"},{"op":"fault","action":"delay","ms":600,"count":1},)"
                      R"({"op":"fault","action":"status","status":403,"count":-1}])");
        std::vector<unsigned char> a(10000), b(10000);
        std::promise<std::exception_ptr> aDone, bDone;
        store.readCoveringAsync(100000, a.size(), a.data(), {}, {}, nullptr,
                                [&](std::exception_ptr e) { aDone.set_value(e); });
        std::this_thread::sleep_for(std::chrono::milliseconds(150));  // a's request is at the server
        store.readCoveringAsync(200000, b.size(), b.data(), {}, {}, nullptr,
                                [&](std::exception_ptr e) { bDone.set_value(e); }, alone);
        EXPECT_TRUE(bDone.get_future().get() != nullptr) << "the refused read succeeded";
        const std::exception_ptr aError = aDone.get_future().get();
        EXPECT_EQ(aError == nullptr, alone);
    }
}

// A Content-Range is three unsigned decimals after the unit, in any case; anything else is no
// range ("-1" had been read as 2^64 - 1, an object's size at the open).
TEST(HttpAnswer, AContentRangeIsThreeUnsignedNumbers) {
    using http_answer::parseContentRange;
    EXPECT_EQ(parseContentRange("bytes 0-99/1000"), (std::array<uint64_t, 3>{0, 99, 1000}));
    EXPECT_EQ(parseContentRange("Bytes 5-5/6\r\n"), (std::array<uint64_t, 3>{5, 5, 6}));
    for (const char* bad : {"bytes 0-99/-1", "bytes -1-99/1000", "bytes 0-99/1000x", "bytes 0 -99/1000",
                            "bytes 0-99", "bytes */1000", "bytes 10-9/1000", "bytes 0-1000/1000", "items 0-9/10",
                            "bytes +0-9/10", "bytes 0-99/99999999999999999999999", ""})
        EXPECT_FALSE(parseContentRange(bad).has_value()) << bad;
}

// `vdiso serve` on a store whose server drips: a frame whose reads pass the deadline ends with
// an error to its viewer; Ctrl-C during such a frame stops the server within 2 s.
TEST_F(RemoteHostile, ServeOnADrippingStoreEndsFramesAndStopsOnCtrlC) {
    LoopbackServer server = s3({"--public", "bkt"});
    const int port = server.port();
    const std::string endpoint = "http://127.0.0.1:" + std::to_string(port), token = "0123456789abcdef0123";
    test::ServeProcess serve({"s3://bkt/head.vdiso", "--no-sign-request", "--s3-endpoint", endpoint, "--port", "0",
                              "--threads", "1", "--token", token, "--iso", "600.5", "--remote-deadline", "2"});
    ASSERT_NE(serve.port(), 0) << "the server did not start";
    const uint16_t servePort = serve.port();

    control(port, R"([{"op":"fault","action":"throttle","bps":2,"count":-1}])");
    const BrickStoreReader local(file("bkt/head.vdiso"));
    const VolumeInfo& v = local.volume();
    auto view = [&](uint32_t seq) {
        Camera camera = orbitCameras(ViewPreset::Normal, v.origin, v.worldMax(), 128, 128, 36)[seq % 36];
        fitClipPlanes(camera, v.origin, v.worldMax());
        return serve::viewMessage(camera, seq, 0, 600.5);
    };
    serve::ViewerClient viewer("127.0.0.1", servePort, token);
    const Clock::time_point start = Clock::now();
    const serve::ClientFrame failed = viewer.requestFrame(view(1));
    EXPECT_EQ(failed.status, "error") << failed.frameEnd;
    ASSERT_FALSE(failed.errors.empty());
    EXPECT_NE(failed.errors[0].find("--remote-deadline"), std::string::npos) << failed.errors[0];
    EXPECT_LT(secondsSince(start), 20.0);

    // Again, and Ctrl-C while its reads drip.
    viewer.sendView(view(2));
    std::this_thread::sleep_for(std::chrono::milliseconds(700));
    const Clock::time_point interrupted = Clock::now();
    ::kill(serve.pid(), SIGINT);
    const int status = serve.wait();
    EXPECT_LT(secondsSince(interrupted), 2.0);
    EXPECT_TRUE(WIFEXITED(status)) << status;
}

// The same server in this process (as vdiso.serve runs it from Python): stop() returns within
// 2 s while a frame's reads drip, with no interrupt of the process.
TEST_F(RemoteHostile, AServerInProcessStopsPromptlyWhileItsReadsDrip) {
    LoopbackServer server = s3({"--public", "bkt"});
    const int port = server.port();
    test::writeWebRoot(mDir);
    serve::ServeOptions o;
    o.stores = {"s3://bkt/head.vdiso"};
    o.remote.s3Endpoint = "http://127.0.0.1:" + std::to_string(port);
    o.remote.anonymous = true;
    o.port = 0;
    o.webRoot = file("web");
    o.iso = 600.5;
    serve::Server serving(o);
    std::thread running([&] { serving.run(); });
    control(port, R"([{"op":"fault","action":"throttle","bps":2,"count":-1}])");
    const BrickStoreReader local(file("bkt/head.vdiso"));
    const VolumeInfo& v = local.volume();
    Camera camera = orbitCameras(ViewPreset::Normal, v.origin, v.worldMax(), 128, 128, 36)[0];
    fitClipPlanes(camera, v.origin, v.worldMax());
    serve::ViewerClient viewer("127.0.0.1", serving.port(), serving.token());
    viewer.sendView(serve::viewMessage(camera, 1, 0, 600.5));
    std::this_thread::sleep_for(std::chrono::milliseconds(700));
    const Clock::time_point stopping = Clock::now();
    serving.stop();
    running.join();
    EXPECT_LT(secondsSince(stopping), 2.0);
    EXPECT_FALSE(interruptRequested());
    viewer.interrupt();  // the stopped server's socket stays open until it is destroyed
}

}  // namespace
}  // namespace vdiso
