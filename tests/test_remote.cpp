// Stores at URLs (io/remote/remote_file.h) against real servers on loopback, started here:
// Debian's nginx serving a folder, and an S3-style server whose SigV4 check is botocore's
// (tests/remote/README.md). Pictures, meshes and `info` from a URL equal the local file's; every
// bad moment (a status, a truncated body, a wrong Content-Range, a server that never answers or
// dies, a redirect loop, a TLS failure, an object replaced while read) is an error naming the URL.
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <cstdlib>
#include <chrono>
#include <string>
#include <thread>
#include <vector>

#include "io/store/brick_store.h"
#include "io/error.h"
#include "io/remote/remote_session.h"
#include "io/remote/s3_location.h"
#include "tests/loopback_servers.h"
#include "tests/test_util.h"

namespace vdiso {
namespace {

const std::string kSource = VDISO_SOURCE_DIR;

using test::LoopbackServer;
using test::s3Env;
constexpr const char* kKey = test::kS3Key;
constexpr const char* kSecret = test::kS3Secret;
constexpr const char* kToken = test::kS3Token;

class RemoteStore : public ::testing::Test {
protected:
    void SetUp() override {
        std::filesystem::create_directories(mDir.path() / "bkt");
        const test::CommandResult r = test::runVdiso("synth " + file("bkt/head.vdiso") +
                                                     " --kind head --size 96 --quiet");
        ASSERT_EQ(r.exitCode, 0) << r.output;
    }
    std::string file(const std::string& name) const { return mDir.file(name); }

    LoopbackServer nginx(const std::vector<std::string>& extra = {}) {
        return test::startNginx(file("bkt"), mDir.path().string(), file("nginx.log"), extra);
    }
    LoopbackServer s3(const std::vector<std::string>& extra = {}) {
        return test::startS3(mDir.path().string(), file("s3.log"), extra);
    }
    static void control(int port, const std::string& json) { ASSERT_TRUE(test::controlS3(port, json)); }
    // extract's picture, its PLY and its stats, for a store at `location`.
    test::CommandResult extract(const std::string& prefix, const std::string& location, const std::string& name,
                                const std::string& extra = "") {
        return test::runCommand(prefix + VDISO_BINARY + " extract '" + location +
                                "' --iso 600.5 --method sage --size 256x256 --png " + file(name + ".png") +
                                " -o " + file(name + ".ply") + " --stats " + file(name + ".json") + " " + extra);
    }
    void expectSameAsLocal(const std::string& name) {
        static bool local = false;
        if (!local || !std::filesystem::exists(file("local.png"))) {
            const test::CommandResult r = extract("", file("bkt/head.vdiso"), "local");
            ASSERT_EQ(r.exitCode, 0) << r.output;
            local = true;
        }
        EXPECT_EQ(test::readFile(file(name + ".png")), test::readFile(file("local.png"))) << name;
        EXPECT_EQ(test::readFile(file(name + ".ply")), test::readFile(file("local.ply"))) << name;
    }
    static void expectError(const test::CommandResult& r, std::initializer_list<std::string> parts) {
        EXPECT_EQ(r.exitCode, 1) << r.output;
        for (const std::string& p : parts) EXPECT_NE(r.output.find(p), std::string::npos) << p << " not in: " << r.output;
    }

    test::ScratchDir mDir;
};

TEST_F(RemoteStore, NginxServesTheSamePicturesMeshesAndInfo) {
    LoopbackServer server = nginx();
    const std::string url = "http://127.0.0.1:" + std::to_string(server.port()) + "/head.vdiso";
    test::CommandResult r = extract("", url, "http");
    ASSERT_EQ(r.exitCode, 0) << r.output;
    expectSameAsLocal("http");
    const std::string stats = test::readText(file("http.json"));
    EXPECT_NE(stats.find("\"read_method\": \"http\""), std::string::npos) << stats;
    EXPECT_NE(stats.find("\"file\": \"" + url + "\""), std::string::npos) << stats;
    // Only what the view needs crossed: the header, the index, and the local run's brick bytes
    // with at most 30% more read ahead on speculation (core/extract/brick_look_ahead.h: a store at a
    // URL has bricks read before they are known to show, where a disk has only 2).
    const BrickStoreReader local(file("bkt/head.vdiso"));
    const auto number = [](const std::string& json, const std::string& key) {
        const size_t at = json.find("\"" + key + "\": ");
        return at == std::string::npos ? -1.0 : std::stod(json.substr(at + key.size() + 4));
    };
    const std::string localStats = test::readText(file("local.json"));
    EXPECT_LE(number(stats, "remote_bytes"),
              1.3 * number(localStats, "bytes_read") + double(kStoreHeaderBytes + local.header().indexBytes));
    EXPECT_LT(number(stats, "remote_bytes"), double(local.fileBytes()) * 0.9);
    // store_bytes counts every byte read from the store since the open: a remote run's are the
    // bytes it fetched; a local run's the header, the index's parts and the bricks it read.
    EXPECT_EQ(number(stats, "store_bytes"), number(stats, "remote_bytes")) << stats;
    EXPECT_GE(number(localStats, "store_bytes"), number(localStats, "bytes_read") + double(kStoreHeaderBytes)) << localStats;
    EXPECT_LE(number(localStats, "store_bytes"), double(local.fileBytes())) << localStats;

    // info reads the same header, index and histogram; a query in the URL is not shown.
    const test::CommandResult remoteInfo = test::runVdiso("info --json '" + url + "?X-Amz-Signature=secret'");
    const test::CommandResult localInfo = test::runVdiso("info --json " + file("bkt/head.vdiso"));
    ASSERT_EQ(remoteInfo.exitCode, 0) << remoteInfo.output;
    EXPECT_EQ(remoteInfo.output.find("secret"), std::string::npos) << remoteInfo.output;
    auto withoutFile = [](std::string json) { return json.substr(json.find("\"format_version\"")); };
    EXPECT_EQ(withoutFile(remoteInfo.output), withoutFile(localInfo.output));
    const test::CommandResult remoteText = test::runVdiso("info '" + url + "?X-Amz-Signature=secret'");
    ASSERT_EQ(remoteText.exitCode, 0) << remoteText.output;
    EXPECT_EQ(remoteText.output.find("secret"), std::string::npos) << remoteText.output;
    EXPECT_NE(remoteText.output.find(url + "\n"), std::string::npos) << remoteText.output;

    r = test::runVdiso("info http://127.0.0.1:" + std::to_string(server.port()) + "/missing.vdiso");
    expectError(r, {"/missing.vdiso", "HTTP 404 (Not Found)"});
}

// The benches' link (tests/remote/link_proxy.cpp) in front of nginx: what crosses it is what
// nginx sent (the same pictures and meshes, ranges and ETags), each request held its delay.
TEST_F(RemoteStore, TheBenchLinkPassesAnswersAsSentAfterItsDelay) {
    LoopbackServer server = nginx();
    LoopbackServer link = test::startLinkProxy(server.port(), 150, 100, file("link.log"));
    const std::string url = "http://127.0.0.1:" + std::to_string(link.port()) + "/head.vdiso";
    const test::CommandResult r = extract("", url, "link");
    ASSERT_EQ(r.exitCode, 0) << r.output;
    expectSameAsLocal("link");
    const auto start = std::chrono::steady_clock::now();
    const test::CommandResult range =
        test::runCommand("curl -sf -D - -o /dev/null -r 4096-8191 " + url);
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    ASSERT_EQ(range.exitCode, 0) << range.output;
    EXPECT_NE(range.output.find("206"), std::string::npos) << range.output;
    EXPECT_NE(range.output.find("Content-Range: bytes 4096-8191/"), std::string::npos) << range.output;
    EXPECT_NE(range.output.find("ETag: \""), std::string::npos) << range.output;
    EXPECT_GE(seconds, 0.15);  // the request was held its delay
}

// A store at a URL reads its index's entries at open and its sub-block codes as views need
// them (io/store/lazy_index.h). A corrupt part of codes: the local `info`, which reads the whole
// index, refuses the store, the remote `info` never reads that part, and a view that needs it (a
// distant one, whose coarse bricks' codes lie in the last part) is an error naming the URL and the
// part, as it is for the local file.
TEST_F(RemoteStore, SubBlockCodesAreReadAsViewsNeedThem) {
    // 9,161 bricks of all levels: a raw index of two parts, the second holding codes only.
    test::CommandResult r = test::runVdiso("synth " + file("bkt/fine.vdiso") + " --kind head --size 160 --brick 8 --quiet");
    ASSERT_EQ(r.exitCode, 0) << r.output;
    std::vector<unsigned char> bytes = test::readFile(file("bkt/fine.vdiso"));
    bytes[bytes.size() - 20] ^= 0x10;  // inside the last part's stored bytes
    test::writeFile(file("bkt/broken.vdiso"), bytes.data(), bytes.size());
    LoopbackServer server = nginx();
    const std::string url = "http://127.0.0.1:" + std::to_string(server.port()) + "/";

    r = test::runVdiso("info " + file("bkt/broken.vdiso"));
    expectError(r, {"broken.vdiso", "index part 1 of 2 is corrupt"});
    r = test::runVdiso("info " + url + "broken.vdiso");
    EXPECT_EQ(r.exitCode, 0) << r.output;
    const std::string view = " extract --iso 600.5 --method sage --lod-error 1 --size 128x128 --view distant -o ";
    r = test::runCommand(std::string(VDISO_BINARY) + view + file("broken.ply") + " '" + url + "broken.vdiso'");
    expectError(r, {url + "broken.vdiso", "index part 1 of 2 is corrupt"});
    EXPECT_FALSE(std::filesystem::exists(file("broken.ply")));
    r = test::runCommand(std::string(VDISO_BINARY) + view + file("broken.ply") + " '" + file("bkt/broken.vdiso") + "'");
    expectError(r, {"broken.vdiso", "index part 1 of 2 is corrupt"});
    EXPECT_FALSE(std::filesystem::exists(file("broken.ply")));

    // The intact store gives the local file's mesh, from every part.
    for (const std::string& place : {file("bkt/fine.vdiso"), url + "fine.vdiso"}) {
        const std::string out = file(place == url + "fine.vdiso" ? "remote.ply" : "local_fine.ply");
        r = test::runCommand(std::string(VDISO_BINARY) + view + out + " '" + place + "'");
        ASSERT_EQ(r.exitCode, 0) << r.output;
    }
    EXPECT_EQ(test::readFile(file("remote.ply")), test::readFile(file("local_fine.ply")));
}

TEST_F(RemoteStore, S3SignedWithEnvironmentOrProfilePathOrVirtualHost) {
    LoopbackServer server = s3();
    const int port = server.port();
    ASSERT_EQ(extract(s3Env(port), "s3://bkt/head.vdiso", "s3").exitCode, 0);
    expectSameAsLocal("s3");
    EXPECT_NE(test::readText(file("s3.json")).find("\"read_method\": \"s3\""), std::string::npos);

    // Virtual-host addressing: bkt.localhost resolves to loopback.
    test::CommandResult r = extract(s3Env(port), "s3://bkt/head.vdiso", "vhost",
                                    "--s3-addressing virtual --s3-endpoint http://localhost:" + std::to_string(port));
    ASSERT_EQ(r.exitCode, 0) << r.output;
    expectSameAsLocal("vhost");

    // Credentials from a profile of the shared credentials file.
    test::writeFile(file("credentials"), "[other]\naws_access_key_id = nobody\naws_secret_access_key = x\n\n"
                                         "[vdiso]\naws_access_key_id = " + std::string(kKey) +
                                         "\naws_secret_access_key = " + kSecret + "\naws_session_token = " + kToken + "\n");
    r = extract("env -u AWS_ACCESS_KEY_ID -u AWS_SECRET_ACCESS_KEY -u AWS_SESSION_TOKEN AWS_PROFILE=vdiso "
                "AWS_SHARED_CREDENTIALS_FILE=" + file("credentials") + " AWS_CONFIG_FILE=/nonexistent "
                "AWS_REGION=us-east-1 ",
                "s3://bkt/head.vdiso", "profile", "--s3-endpoint http://127.0.0.1:" + std::to_string(port));
    ASSERT_EQ(r.exitCode, 0) << r.output;
    expectSameAsLocal("profile");
}

// A view's requests reuse the pool's connections (kept alive, up to --connections of them):
// with libcurl's default cache of 5, a pool of 8 readers closed most connections after one
// request each, and every request paid a connect.
TEST_F(RemoteStore, RequestsReuseThePoolsConnections) {
    // Bricks of 8: a view of about a hundred requests, many in flight at once behind the delay.
    test::CommandResult r = test::runVdiso("synth " + file("bkt/fine.vdiso") + " --kind head --size 96 --brick 8 --quiet");
    ASSERT_EQ(r.exitCode, 0) << r.output;
    LoopbackServer server = s3({"--delay-ms", "20"});
    const int port = server.port();
    r = extract(s3Env(port), "s3://bkt/fine.vdiso", "pool", "--connections 8");
    ASSERT_EQ(r.exitCode, 0) << r.output;
    const test::CommandResult stats =
        test::runCommand("curl -sf 'http://127.0.0.1:" + std::to_string(port) + "/__stats?log=0'");
    ASSERT_EQ(stats.exitCode, 0) << stats.output;
    const nlohmann::json total = nlohmann::json::parse(stats.output)["total"];
    const int64_t requests = total["requests"].get<int64_t>(), connections = total["connections"].get<int64_t>();
    EXPECT_GE(requests, 40) << stats.output;
    EXPECT_LE(connections - 1, 8) << requests << " requests";  // less this request's own
}

// libcurl is loaded when remote data is first read (io/remote/curl_library.h): a local store
// needs none, and a URL without it is an error naming the URL and what is missing.
TEST_F(RemoteStore, LocalDataNeedsNoLibcurlAndAUrlWithoutItIsNamed) {
    const std::string noCurl = "VDISO_CURL_LIBRARY=/nonexistent/libcurl.so.4 ";
    test::CommandResult r = test::runCommand(noCurl + VDISO_BINARY + " info " + file("bkt/head.vdiso"));
    EXPECT_EQ(r.exitCode, 0) << r.output;
    for (const std::string url : {"http://127.0.0.1:9/head.vdiso", "s3://bkt/head.vdiso", "http://127.0.0.1:9/z.zarr"}) {
        r = test::runCommand(noCurl + VDISO_BINARY + " extract " + url + " --iso 600.5 --png " + file("none.png"));
        EXPECT_EQ(r.exitCode, 1) << r.output;
        EXPECT_NE(r.output.find(url + ": cannot load /nonexistent/libcurl.so.4"), std::string::npos) << r.output;
        EXPECT_NE(r.output.find("remote data cannot be read"), std::string::npos) << r.output;
        EXPECT_FALSE(std::filesystem::exists(file("none.png")));
    }
}

TEST_F(RemoteStore, S3RefusalsAreNamed) {
    LoopbackServer server = s3({"--public", "open"});
    const int port = server.port();
    const std::string env = s3Env(port);
    // The signature is checked by botocore, not by us: a wrong secret is refused.
    test::CommandResult r = extract(env + "AWS_SECRET_ACCESS_KEY=wrong ", "s3://bkt/head.vdiso", "bad");
    expectError(r, {"s3://bkt/head.vdiso", "HTTP 403 (Forbidden): SignatureDoesNotMatch"});
    EXPECT_FALSE(std::filesystem::exists(file("bad.png")));
    // Without credentials a private bucket is refused; a public one reads anonymously.
    r = extract(env, "s3://bkt/head.vdiso", "anon", "--no-sign-request");
    expectError(r, {"s3://bkt/head.vdiso", "HTTP 403 (Forbidden): AccessDenied"});
    std::filesystem::create_directories(mDir.path() / "open");
    std::filesystem::copy_file(file("bkt/head.vdiso"), file("open/head.vdiso"));
    r = extract(env, "s3://open/head.vdiso", "public", "--no-sign-request");
    ASSERT_EQ(r.exitCode, 0) << r.output;
    expectSameAsLocal("public");
    r = extract(env, "s3://bkt/nothere.vdiso", "none");
    expectError(r, {"s3://bkt/nothere.vdiso", "HTTP 404 (Not Found): NoSuchKey"});
    r = test::runVdiso("info s3://bucket-only");
    expectError(r, {"s3://bucket-only", "a bucket and a key"});
}

TEST_F(RemoteStore, PassingFailuresAreTriedAgain) {
    LoopbackServer server = s3();
    const int port = server.port();
    // Two 503s, a truncated body, a dropped connection: each request is tried again.
    control(port, R"([{"op":"fault","action":"status","status":503,"count":2,"skip":3},)"
                  R"({"op":"fault","action":"truncate","bytes":100,"count":1,"skip":6},)"
                  R"({"op":"fault","action":"drop","count":1,"skip":9}])");
    const test::CommandResult r = extract(s3Env(port), "s3://bkt/head.vdiso", "retried");
    ASSERT_EQ(r.exitCode, 0) << r.output;
    expectSameAsLocal("retried");
}

// A request without an answer for many times the usual wait is a straggler: ended and sent
// again at once, where waiting for the stall timeout (60 s here) would hold the view.
TEST_F(RemoteStore, AStragglerIsSentAgain) {
    LoopbackServer server = s3();
    const int port = server.port();
    control(port, R"([{"op":"fault","action":"hang","count":1,"skip":12}])");  // a brick: the view sends 25-28
    const test::CommandResult r = extract("timeout 40 " + s3Env(port), "s3://bkt/head.vdiso", "straggler",
                                          "--remote-timeout 60");
    ASSERT_EQ(r.exitCode, 0) << r.output;
    expectSameAsLocal("straggler");
    const std::string stats = test::readText(file("straggler.json"));
    EXPECT_NE(stats.find("\"remote_stragglers\": 1"), std::string::npos) << stats;
}

TEST_F(RemoteStore, BadMomentsAreErrorsNamingTheUrl) {
    LoopbackServer server = s3();
    const int port = server.port();
    const std::string env = s3Env(port);
    struct Case {
        const char* fault;
        std::vector<std::string> parts;
    };
    const Case cases[] = {
        {R"({"op":"fault","action":"status","status":500,"count":-1,"skip":2})", {"HTTP 500", "tried 4 times"}},
        {R"({"op":"fault","action":"status","status":403,"count":-1,"skip":2})", {"HTTP 403 (Forbidden)"}},
        {R"({"op":"fault","action":"truncate","bytes":10,"count":-1,"skip":2})", {"tried 4 times"}},
        {R"({"op":"fault","action":"bad_content_range","count":-1,"skip":2})", {"Content-Range"}},
        {R"({"op":"fault","action":"ignore_range","count":-1})", {"without byte ranges"}},
        {R"({"op":"fault","action":"redirect","status":307,"count":-1})", {"redirects too often"}},
        {R"({"op":"fault","action":"hang","count":-1,"skip":2})", {"tried 4 times"}},
    };
    for (const Case& c : cases) {
        SCOPED_TRACE(c.fault);
        control(port, std::string("[{\"op\":\"clear_faults\"},") + c.fault + "]");
        const test::CommandResult r = extract(env, "s3://bkt/head.vdiso", "bad", "--remote-timeout 1 --force");
        EXPECT_EQ(r.exitCode, 1) << r.output;
        EXPECT_NE(r.output.find("s3://bkt/head.vdiso"), std::string::npos) << r.output;
        for (const std::string& p : c.parts) EXPECT_NE(r.output.find(p), std::string::npos) << p << ": " << r.output;
        EXPECT_FALSE(std::filesystem::exists(file("bad.png")));
        EXPECT_FALSE(std::filesystem::exists(file("bad.ply")));
    }
}

TEST_F(RemoteStore, ObjectReplacedWhileReadIsAnError) {
    LoopbackServer server = s3();
    const int port = server.port();
    StoreOpenOptions options;
    options.remote.s3Endpoint = "http://127.0.0.1:" + std::to_string(port);
    ::setenv("AWS_ACCESS_KEY_ID", kKey, 1);
    ::setenv("AWS_SECRET_ACCESS_KEY", kSecret, 1);
    ::setenv("AWS_SESSION_TOKEN", kToken, 1);
    const BrickStoreReader store("s3://bkt/head.vdiso", options);
    std::vector<unsigned char> brick(store.brickBytes());
    store.readBrick(0, brick.data());
    // The same size, other bytes: only the pinned ETag tells.
    std::vector<unsigned char> other = test::readFile(file("bkt/head.vdiso"));
    other[other.size() / 2] ^= 1;
    test::writeFile(file("bkt/head.vdiso"), other.data(), other.size());
    try {
        store.readBrick(1, brick.data());
        ADD_FAILURE() << "read a brick of the replaced object";
    } catch (const IoError& e) {
        EXPECT_NE(std::string(e.what()).find("s3://bkt/head.vdiso: was replaced while being read"), std::string::npos)
            << e.what();
    }
    ::unsetenv("AWS_ACCESS_KEY_ID");
    ::unsetenv("AWS_SECRET_ACCESS_KEY");
    ::unsetenv("AWS_SESSION_TOKEN");
}

TEST_F(RemoteStore, ServerDyingMidReadIsAnError) {
    LoopbackServer server = nginx();
    const std::string url = "http://127.0.0.1:" + std::to_string(server.port()) + "/head.vdiso";
    StoreOpenOptions options;
    options.remote.attempts = 2;
    const BrickStoreReader store(url, options);
    std::vector<unsigned char> brick(store.brickBytes());
    store.readBrick(0, brick.data());
    server.stop();
    try {
        store.readBrick(1, brick.data());
        ADD_FAILURE() << "read a brick from a stopped server";
    } catch (const IoError& e) {
        EXPECT_NE(std::string(e.what()).find(url + ": "), std::string::npos) << e.what();
        EXPECT_NE(std::string(e.what()).find("tried 2 times"), std::string::npos) << e.what();
    }
}

// --disk-cache keeps fetched ranges across runs and processes: a second run fetches only the
// header that pins the version and reads the rest from the cache; two processes share it at
// once; a damaged entry is fetched again; a new version of the object drops the old one's
// entries; the bound holds; a folder that cannot be a cache is refused by name.
TEST_F(RemoteStore, DiskCacheKeepsRangesAcrossRuns) {
    LoopbackServer server = s3();
    const std::string env = s3Env(server.port());
    const std::string cache = file("cache");
    const auto number = [](const std::string& json, const std::string& key) {
        const size_t at = json.find("\"" + key + "\": ");
        return at == std::string::npos ? -1.0 : std::stod(json.substr(at + key.size() + 4));
    };
    auto run = [&](const std::string& name, const std::string& extra = "") {
        const test::CommandResult r = extract(env, "s3://bkt/head.vdiso", name, "--disk-cache " + cache + " " + extra);
        EXPECT_EQ(r.exitCode, 0) << r.output;
        expectSameAsLocal(name);
        return test::readText(file(name + ".json"));
    };
    // Without read-ahead, so that both runs read the same bricks: the look-ahead's speculation
    // depends on timing, and 2 bricks more or fewer in one run broke either bound below (twice
    // in about 20 runs, 2026-11-30).
    const std::string first = run("first", "--prefetch 0");
    EXPECT_EQ(number(first, "disk_cache_hits"), 0.0) << first;
    const std::string second = run("second", "--prefetch 0");
    // The header, which pins the version, crosses again; the rest comes from the cache.
    EXPECT_LE(number(second, "remote_bytes"),
              double(kStoreHeaderBytes) + 0.1 * number(first, "remote_bytes")) << first << second;
    EXPECT_GE(number(second, "disk_cache_bytes"), 0.9 * (number(first, "remote_bytes") - kStoreHeaderBytes))
        << first << second;

    // Two processes at once, and damaged entries: each still gets the very picture.
    std::vector<std::filesystem::path> entries;
    for (const auto& e : std::filesystem::recursive_directory_iterator(cache))
        if (e.is_regular_file()) entries.push_back(e.path());
    ASSERT_GT(entries.size(), 2u);
    for (size_t i = 0; i < entries.size(); i += 3) {
        std::vector<unsigned char> bytes = test::readFile(entries[i].string());
        bytes[bytes.size() / 2] ^= 0x40;
        test::writeFile(entries[i].string(), bytes.data(), bytes.size());
    }
    // Meshes only: two processes drawing with OSMesa at once made LeakSanitizer's exit-time
    // thread stop crash ("Tracer caught signal 11"; scripts/sanitize.sh on llvmpipe's threads).
    const test::CommandResult both = test::runCommand(
        "(" + env + VDISO_BINARY + " extract s3://bkt/head.vdiso --iso 600.5 --method sage --size 256x256 -o " +
        file("p1.ply") + " --disk-cache " + cache + " & " + env + VDISO_BINARY +
        " extract s3://bkt/head.vdiso --iso 600.5 --method sage --size 256x256 -o " + file("p2.ply") +
        " --disk-cache " + cache + "; s=$?; wait $! && exit $s)");
    ASSERT_EQ(both.exitCode, 0) << both.output;
    EXPECT_EQ(test::readFile(file("p1.ply")), test::readFile(file("local.ply")));
    EXPECT_EQ(test::readFile(file("p2.ply")), test::readFile(file("local.ply")));

    // A new version of the object: the old one's entries go, and nothing of them is read.
    const test::CommandResult other = test::runVdiso("synth " + file("bkt/head.vdiso") +
                                                     " --kind head --size 80 --quiet --force");
    ASSERT_EQ(other.exitCode, 0) << other.output;
    const test::CommandResult r = extract(env, "s3://bkt/head.vdiso", "new", "--disk-cache " + cache);
    ASSERT_EQ(r.exitCode, 0) << r.output;
    EXPECT_EQ(number(test::readText(file("new.json")), "disk_cache_hits"), 0.0);
    size_t versions = 0;
    for (const auto& object : std::filesystem::directory_iterator(cache))
        for (const auto& version : std::filesystem::directory_iterator(object)) versions += version.is_directory();
    EXPECT_EQ(versions, 1u);

    // At most 1 MB kept: another object's old 2 MB entry goes first.
    std::filesystem::create_directories(cache + "/0123456789abcdef/0123456789abcdef");
    const std::string old = cache + "/0123456789abcdef/0123456789abcdef/0-2097148";
    test::writeFile(old, std::string(size_t(2) << 20, 'x'));
    std::filesystem::last_write_time(old, std::filesystem::file_time_type::clock::now() - std::chrono::hours(24));
    ASSERT_EQ(extract(env, "s3://bkt/head.vdiso", "bounded", "--disk-cache " + cache + " --disk-cache-mb 1").exitCode, 0);
    EXPECT_EQ(test::readFile(file("bounded.png")), test::readFile(file("new.png")));
    uint64_t total = 0;
    for (const auto& e : std::filesystem::recursive_directory_iterator(cache))
        if (e.is_regular_file()) total += e.file_size();
    EXPECT_LE(total, uint64_t(1) << 20);
    EXPECT_FALSE(std::filesystem::exists(old));
    EXPECT_GT(total, 0u);

    const test::CommandResult refused = extract(env, "s3://bkt/head.vdiso", "refused", "--disk-cache /proc/vdiso-cache");
    expectError(refused, {"/proc/vdiso-cache", "disk cache"});
}

TEST_F(RemoteStore, HttpsNeedsTheRightAuthority) {
    // Under AddressSanitizer, LeakSanitizer's exit-time check ended the vdiso child of this
    // test with "LeakSanitizer has encountered a fatal error" after an HTTPS run (OpenSSL's
    // threads); not yet understood, so the Release run alone covers HTTPS.
    if (VDISO_UNDER_ASAN) GTEST_SKIP() << "LeakSanitizer fails at the exit of an HTTPS run";
    ASSERT_EQ(test::runCommand("sh " + kSource + "/tests/remote/gen_cert.sh " + mDir.path().string() +
                               " && sh " + kSource + "/tests/remote/gen_cert.sh " + mDir.path().string() + " other")
                  .exitCode,
              0);
    LoopbackServer server = nginx({"--tls", file("server.crt"), file("server.key")});
    const std::string url = "https://localhost:" + std::to_string(server.port()) + "/head.vdiso";
    test::CommandResult r = extract("", url, "https", "--ca-file " + file("server.crt"));
    ASSERT_EQ(r.exitCode, 0) << r.output;
    expectSameAsLocal("https");
    r = extract("", url, "tls", "--ca-file " + file("other.crt"));
    expectError(r, {url, "certificate"});
}

}  // namespace
}  // namespace vdiso

namespace vdiso {

// A session resolves a bucket's endpoint, region and credentials once: every Zarr chunk of a
// bucket reuses them (the environment and AWS's files are read for its first object only), and
// the URL of each key is the one a fresh resolution gives.
TEST(RemoteSessionS3, ResolvesABucketOnceAndEachKeyAsAlone) {
    setenv("AWS_ACCESS_KEY_ID", "AKIDFIRST", 1);
    setenv("AWS_SECRET_ACCESS_KEY", "first-secret", 1);
    setenv("AWS_REGION", "eu-west-3", 1);
    setenv("AWS_SHARED_CREDENTIALS_FILE", "/nonexistent", 1);
    setenv("AWS_CONFIG_FILE", "/nonexistent", 1);
    for (const S3Addressing addressing : {S3Addressing::Path, S3Addressing::VirtualHost}) {
        RemoteOptions options;
        options.s3Endpoint = "http://127.0.0.1:9";
        options.s3Addressing = addressing;
        RemoteSession session(options);
        const S3Location first = session.s3Location("s3://bucket/a/0.0.0");
        EXPECT_EQ(first.url, resolveS3Location("s3://bucket/a/0.0.0", options).url);
        setenv("AWS_ACCESS_KEY_ID", "AKIDSECOND", 1);
        const S3Location second = session.s3Location("s3://bucket/a/b c+1");
        EXPECT_EQ(second.accessKey, "AKIDFIRST");
        EXPECT_EQ(second.region, "eu-west-3");
        EXPECT_EQ(second.key, "a/b c+1");
        EXPECT_EQ(second.url, resolveS3Location("s3://bucket/a/b c+1", options).url);
        EXPECT_EQ(resolveS3Location("s3://bucket/a/b c+1", options).accessKey, "AKIDSECOND");
        EXPECT_EQ(session.s3Location("s3://other/k").accessKey, "AKIDSECOND");  // a new bucket: resolved
        EXPECT_THROW(session.s3Location("s3://bucket"), IoError);
        setenv("AWS_ACCESS_KEY_ID", "AKIDFIRST", 1);
    }
    for (const char* name : {"AWS_ACCESS_KEY_ID", "AWS_SECRET_ACCESS_KEY", "AWS_REGION",
                             "AWS_SHARED_CREDENTIALS_FILE", "AWS_CONFIG_FILE"})
        unsetenv(name);
}

}  // namespace vdiso
