// Real servers on loopback for the remote tests (tests/remote/README.md): Debian's nginx
// serving a folder, and the S3-style server whose SigV4 check is botocore's. Each is a child
// process holding a pipe on its stdin: it stops when this object goes or this process dies.
#pragma once

#include <sys/types.h>

#include <string>
#include <vector>

namespace vdiso::test {

class LoopbackServer {
public:
    // Starts argv (its stderr appended to `log`) and waits for its first line, "PORT n".
    LoopbackServer(const std::vector<std::string>& argv, const std::string& log);
    ~LoopbackServer() { stop(); }
    LoopbackServer(const LoopbackServer&) = delete;
    LoopbackServer& operator=(const LoopbackServer&) = delete;
    LoopbackServer(LoopbackServer&& other) noexcept;
    int port() const { return mPort; }
    // Ends it now (SIGKILL: a server dying, no goodbye).
    void stop();

private:
    pid_t mPid = -1;
    int mStdin = -1, mStdout = -1;
    int mPort = 0;
};

// The credentials the S3 server accepts.
constexpr const char* kS3Key = "AKIDVDISOTEST";
constexpr const char* kS3Secret = "vdiso-test-secret";
constexpr const char* kS3Token = "vdiso-session-token";

// nginx serving `root` (its temp prefix made in `tmpdir`); `extra`: start_nginx.py's options.
LoopbackServer startNginx(const std::string& root, const std::string& tmpdir, const std::string& log,
                          const std::vector<std::string>& extra = {});
// The S3 server over `root` (ROOT/BUCKET/KEY) with the credentials above.
LoopbackServer startS3(const std::string& root, const std::string& log,
                       const std::vector<std::string>& extra = {});
// tests/remote/link_proxy.cpp on 127.0.0.1 in front of `upstreamPort`: each request held
// `delayMs`, answers capped at `rateMbit` (0: none).
LoopbackServer startLinkProxy(int upstreamPort, int delayMs, int rateMbit, const std::string& log);
// "env ..." that gives a command the S3 server's endpoint and the credentials above.
std::string s3Env(int port);
// Posts `json` to the S3 server's /__control (faults, tests/remote/README.md); false on failure.
bool controlS3(int port, const std::string& json);

}  // namespace vdiso::test
