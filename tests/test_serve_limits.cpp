// `vdiso serve` under a process thread limit, as containers set: a child server whose user may
// run only a few threads at once. Viewers take no thread of their own (serve/frame_pool.h), so
// three times as many viewers as the limit are all served; a frame whose read-ahead cannot
// start a thread is answered to its viewer alone, and the server stays up.
#include <gtest/gtest.h>

#include <csignal>
#include <memory>
#include <string>
#include <vector>

#include <sys/resource.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <nlohmann/json.hpp>

#include "core/camera.h"
#include "core/view_presets.h"
#include "io/store/brick_store.h"
#include "serve/protocol.h"
#include "serve/viewer_client.h"
#include "tests/serve_test_util.h"
#include "tests/test_util.h"

namespace vdiso::serve {
namespace {

// A user id no account has: its processes are only the server's, so the thread limit counts
// the server's threads alone (RLIMIT_NPROC counts every process and thread of the real user).
constexpr uid_t kLimitedUser = 54321;
constexpr rlim_t kThreads = 8;

ViewMessage viewOf(const BrickStoreReader& store, uint32_t seq) {
    const VolumeInfo& v = store.volume();
    Camera c = orbitCameras(ViewPreset::Normal, v.origin, v.worldMax(), 96, 96, 36)[seq % 36];
    fitClipPlanes(c, v.origin, v.worldMax());
    return viewMessage(c, seq, 0, 600.5);
}

// What a viewer's first VIEW brings first: "frameBegin" when it is served, the error text when
// it was refused (the server closes it after).
std::string firstAnswer(ViewerClient& client, const BrickStoreReader& store, uint32_t seq) {
    client.sendView(viewOf(store, seq));
    try {
        return client.readText();
    } catch (const std::exception& e) {
        return std::string("closed: ") + e.what();
    }
}

TEST(ServeLimits, AThreadLimitDoesNotLimitTheViewers) {
    if (geteuid() != 0) GTEST_SKIP() << "needs root to run the server as a user of its own";
    test::ScratchDir dir;
    ::chmod(dir.path().c_str(), 0755);  // the server's user reads the store
    const std::string store = dir.file("head.vdiso");
    ASSERT_EQ(test::runVdiso("synth " + store + " --kind head --size 64 --quiet").exitCode, 0);
    ::chmod(store.c_str(), 0644);
    const BrickStoreReader reader(store);
    const std::string token = "0123456789abcdef0123";

    // The server's user may run only kThreads threads at once.
    test::ServeProcess server({store, "--port", "0", "--threads", "1", "--token", token}, [] {
        const rlimit limit{kThreads, kThreads};
        return ::setrlimit(RLIMIT_NPROC, &limit) != 0 || ::setgid(kLimitedUser) != 0 || ::setuid(kLimitedUser) != 0
                   ? 1
                   : 0;
    });
    ASSERT_NE(server.port(), 0) << "the server did not start";
    const uint16_t port = server.port();
    const pid_t pid = server.pid();

    // Viewers join, each served in turn, three times as many as the server may run threads.
    std::vector<std::unique_ptr<ViewerClient>> viewers;
    for (uint32_t k = 1; k <= 3 * kThreads; ++k) {
        viewers.push_back(std::make_unique<ViewerClient>("127.0.0.1", port, token));
        ASSERT_NE(firstAnswer(*viewers.back(), reader, k).find("\"frameBegin\""), std::string::npos) << k;
        EXPECT_EQ(viewers.back()->readFrame(k).status, "complete") << k;
    }
    // All of them at once: each gets its frame (or, where a read-ahead thread could not start,
    // an error of its own); the server stays up.
    for (uint32_t k = 0; k < viewers.size(); ++k) viewers[k]->sendView(viewOf(reader, 100 + k));
    for (uint32_t k = 0; k < viewers.size(); ++k) {
        const std::string status = viewers[k]->readFrame(100 + k).status;
        EXPECT_TRUE(status == "complete" || status == "error") << status;
    }
    EXPECT_EQ(::kill(pid, 0), 0) << "the server is gone";
    viewers.clear();
    ViewerClient fresh("127.0.0.1", port, token);
    EXPECT_EQ(fresh.requestFrame(viewOf(reader, 200)).status, "complete");

    ::kill(pid, SIGINT);
    const int status = server.wait();
    EXPECT_TRUE(WIFEXITED(status)) << status;
}

}  // namespace
}  // namespace vdiso::serve
