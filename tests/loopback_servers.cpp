#include "tests/loopback_servers.h"

#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <unistd.h>

#include <stdexcept>

#include "tests/test_util.h"

namespace vdiso::test {

namespace {
const std::string kSource = VDISO_SOURCE_DIR;
const std::string kPython = "/usr/bin/python3";
}  // namespace

LoopbackServer::LoopbackServer(const std::vector<std::string>& argv, const std::string& log) {
    int in[2], out[2];
    if (::pipe2(in, O_CLOEXEC) != 0 || ::pipe2(out, O_CLOEXEC) != 0) throw std::runtime_error("pipe");
    mPid = ::fork();
    if (mPid == 0) {
        ::setpgid(0, 0);  // its own group, which stop() ends whole (nginx runs under a wrapper)
        ::dup2(in[0], STDIN_FILENO);
        ::dup2(out[1], STDOUT_FILENO);
        const int err = ::open(log.c_str(), O_WRONLY | O_CREAT | O_APPEND, 0644);
        if (err >= 0) ::dup2(err, STDERR_FILENO);
        std::vector<char*> args;
        for (const std::string& a : argv) args.push_back(const_cast<char*>(a.c_str()));
        args.push_back(nullptr);
        ::execv(args[0], args.data());
        ::_exit(127);
    }
    ::close(in[0]);
    ::close(out[1]);
    mStdin = in[1];
    mStdout = out[0];
    std::string line;
    for (char c; line.find('\n') == std::string::npos;) {
        pollfd p{mStdout, POLLIN, 0};
        if (::poll(&p, 1, 20000) <= 0 || ::read(mStdout, &c, 1) != 1) {
            stop();
            throw std::runtime_error("the server did not start: " + readText(log));
        }
        line += c;
    }
    mPort = std::stoi(line.substr(line.find(' ') + 1));
}

LoopbackServer::LoopbackServer(LoopbackServer&& other) noexcept
    : mPid(other.mPid), mStdin(other.mStdin), mStdout(other.mStdout), mPort(other.mPort) {
    other.mPid = -1;
}

void LoopbackServer::stop() {
    if (mPid <= 0) return;
    // The whole group: nginx's master and workers too, not only the wrapper (they would follow
    // it on their parent-death signal, but a moment later, still answering meanwhile).
    ::kill(-mPid, SIGKILL);
    ::kill(mPid, SIGKILL);
    ::waitpid(mPid, nullptr, 0);
    mPid = -1;
    ::close(mStdin);
    ::close(mStdout);
    // Returns once the port takes no connection (at most 10 s).
    for (int wait = 0; wait < 1000 && mPort > 0; ++wait) {
        const int fd = ::socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0);
        sockaddr_in a{};
        a.sin_family = AF_INET;
        a.sin_port = htons(uint16_t(mPort));
        a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
        const bool answered = fd >= 0 && ::connect(fd, reinterpret_cast<const sockaddr*>(&a), sizeof a) == 0;
        if (fd >= 0) ::close(fd);
        if (!answered) break;
        ::usleep(10000);
    }
}

LoopbackServer startNginx(const std::string& root, const std::string& tmpdir, const std::string& log,
                          const std::vector<std::string>& extra) {
    std::vector<std::string> argv = {kPython, kSource + "/tests/remote/start_nginx.py", "--root", root,
                                     "--lifetime", "300", "--tmpdir", tmpdir};
    argv.insert(argv.end(), extra.begin(), extra.end());
    return LoopbackServer(argv, log);
}

LoopbackServer startS3(const std::string& root, const std::string& log, const std::vector<std::string>& extra) {
    std::vector<std::string> argv = {kPython, kSource + "/tests/remote/s3_server.py", "--root", root, "--cred",
                                     std::string(kS3Key) + ":" + kS3Secret + ":" + kS3Token, "--lifetime", "300"};
    argv.insert(argv.end(), extra.begin(), extra.end());
    return LoopbackServer(argv, log);
}

LoopbackServer startLinkProxy(int upstreamPort, int delayMs, int rateMbit, const std::string& log) {
    return LoopbackServer({VDISO_LINK_PROXY, "--upstream", std::to_string(upstreamPort), "--delay-ms",
                           std::to_string(delayMs), "--rate-mbit", std::to_string(rateMbit), "--lifetime", "300"},
                          log);
}

std::string s3Env(int port) {
    return "env AWS_ACCESS_KEY_ID=" + std::string(kS3Key) + " AWS_SECRET_ACCESS_KEY=" + kS3Secret +
           " AWS_SESSION_TOKEN=" + kS3Token + " AWS_ENDPOINT_URL=http://127.0.0.1:" + std::to_string(port) +
           " AWS_REGION=us-east-1 AWS_SHARED_CREDENTIALS_FILE=/nonexistent AWS_CONFIG_FILE=/nonexistent ";
}

bool controlS3(int port, const std::string& json) {
    return runCommand("curl -sf -X POST --data '" + json + "' http://127.0.0.1:" + std::to_string(port) +
                      "/__control")
               .exitCode == 0;
}

}  // namespace vdiso::test
