// `vdiso serve` under a process thread limit, as containers set: a child server whose user may
// run only a few threads at once. A viewer whose worker cannot be started is told so and
// closed alone; the server stays up, the viewers it holds are served, and once threads are
// free again a new viewer is served too.
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
#include "io/store/brick_store.h"
#include "serve/protocol.h"
#include "serve/viewer_client.h"
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

TEST(ServeLimits, AThreadLimitRefusesOneViewerAndTheServerGoesOn) {
    if (geteuid() != 0) GTEST_SKIP() << "needs root to run the server as a user of its own";
    test::ScratchDir dir;
    ::chmod(dir.path().c_str(), 0755);  // the server's user reads the store
    const std::string store = dir.file("head.vdiso");
    ASSERT_EQ(test::runVdiso("synth " + store + " --kind head --size 64 --quiet").exitCode, 0);
    ::chmod(store.c_str(), 0644);
    const BrickStoreReader reader(store);
    const std::string token = "0123456789abcdef0123";

    int out[2];
    ASSERT_EQ(::pipe(out), 0);
    const pid_t pid = ::fork();
    ASSERT_GE(pid, 0);
    if (pid == 0) {  // only async-signal-safe calls until exec
        ::dup2(out[1], 1);
        ::close(out[0]);
        const rlimit limit{kThreads, kThreads};
        if (::setrlimit(RLIMIT_NPROC, &limit) != 0 || ::setgid(kLimitedUser) != 0 || ::setuid(kLimitedUser) != 0)
            ::_exit(126);
        ::execl(VDISO_BINARY, VDISO_BINARY, "serve", store.c_str(), "--port", "0", "--threads", "1",
                "--token", token.c_str(), static_cast<char*>(nullptr));
        ::_exit(127);
    }
    ::close(out[1]);
    // The server goes with the test, whatever ends it.
    struct Stop {
        pid_t pid;
        ~Stop() {
            if (pid <= 0) return;
            ::kill(pid, SIGKILL);
            ::waitpid(pid, nullptr, 0);
        }
    } stop{pid};
    // "vdiso serve: open http://127.0.0.1:PORT/?token=..."
    std::string line;
    char c;
    while (line.find('\n') == std::string::npos && ::read(out[0], &c, 1) == 1) line += c;
    ::close(out[0]);
    const size_t at = line.find("127.0.0.1:");
    ASSERT_NE(at, std::string::npos) << "the server did not start: '" << line << "'";
    const uint16_t port = uint16_t(std::stoi(line.substr(at + 10)));

    // Viewers join until one is refused; each served one keeps its worker thread.
    std::vector<std::unique_ptr<ViewerClient>> viewers;
    std::string refusal;
    for (uint32_t k = 1; k <= 3 * kThreads && refusal.empty(); ++k) {
        std::unique_ptr<ViewerClient> viewer;
        try {  // a refused viewer's first message is the refusal, where a hello was due
            viewer = std::make_unique<ViewerClient>("127.0.0.1", port, token);
        } catch (const std::exception& e) {
            refusal = e.what();
            break;
        }
        const std::string answer = firstAnswer(*viewer, reader, k);
        if (answer.find("\"frameBegin\"") != std::string::npos) {
            viewer->readFrame(k);  // complete, or an error for want of a reader thread: it stays
            viewers.push_back(std::move(viewer));
        } else {
            refusal = answer;
        }
    }
    ASSERT_FALSE(viewers.empty());
    EXPECT_NE(refusal.find("cannot start work for another viewer"), std::string::npos) << refusal;
    EXPECT_EQ(::kill(pid, 0), 0) << "the server is gone";

    // Threads freed: the first viewer, and a new one, are served whole.
    viewers.resize(1);
    ::usleep(300 * 1000);  // the closed viewers' workers end
    EXPECT_EQ(viewers[0]->requestFrame(viewOf(reader, 100)).status, "complete");
    ViewerClient fresh("127.0.0.1", port, token);
    EXPECT_EQ(fresh.requestFrame(viewOf(reader, 101)).status, "complete");

    ::kill(pid, SIGINT);
    int status = 0;
    ::waitpid(pid, &status, 0);
    EXPECT_TRUE(WIFEXITED(status)) << status;
    stop.pid = -1;
}

}  // namespace
}  // namespace vdiso::serve
