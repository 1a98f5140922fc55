// A network link for benches and tests: a TCP proxy on loopback in front of a real server
// (nginx serving a bucket's files, tests/remote/start_nginx.py), which holds each request
// `--delay-ms` before passing it on (the round trip to an object store) and sends the answers'
// bytes no faster than `--rate-mbit` in all (one link's bandwidth, every connection sharing it).
// One thread, no copies beyond one buffer a direction: its CPU a request is a small fraction of
// a client's, so what a bench measures is the client and the link, not the test server (the
// Python S3 server spent as much CPU as vdiso did: issue "remote views at the speed of the link").
//
//   vdiso_link_proxy --upstream PORT [--delay-ms N] [--rate-mbit M] [--lifetime S]
//
// Prints "PORT <n>" (the port it listens on, 127.0.0.1, chosen by the OS) and flushes. Stops when
// its stdin, a pipe, closes, after --lifetime seconds (default 3600), or on SIGTERM/SIGINT.
// A request is what the client sends before it waits: the delay applies to each read from the
// client (an HTTP/1.1 client without pipelining sends one request, then waits for its answer).
#include <boost/asio/ip/tcp.hpp>
#include <boost/asio/posix/stream_descriptor.hpp>
#include <boost/asio/signal_set.hpp>
#include <boost/asio/steady_timer.hpp>
#include <boost/asio/write.hpp>

#include <sys/stat.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <functional>
#include <memory>
#include <string>

namespace asio = boost::asio;
using asio::ip::tcp;
using Clock = std::chrono::steady_clock;

namespace {

struct Link {
    std::chrono::milliseconds delay{0};
    double bytesPerSecond = 0;  // 0: no cap
    Clock::time_point freeAt = Clock::now();  // when the link has sent what it was given

    // When `bytes` given now have crossed the link.
    Clock::time_point send(size_t bytes) {
        if (bytesPerSecond <= 0) return Clock::now();
        const std::chrono::duration<double> carrying(double(bytes) / bytesPerSecond);
        freeAt = std::max(freeAt, Clock::now()) + std::chrono::duration_cast<Clock::duration>(carrying);
        return freeAt;
    }
};

// One client connection and its own upstream connection; lives while either direction runs.
class Pair : public std::enable_shared_from_this<Pair> {
public:
    Pair(asio::io_context& io, tcp::socket client, Link& link)
        : mClient(std::move(client)), mUpstream(io), mUp(io), mDown(io), mLink(link) {}

    void start(const tcp::endpoint& upstream) {
        auto self = shared_from_this();
        mUpstream.async_connect(upstream, [self](boost::system::error_code e) {
            if (e) return self->close();
            self->mUpstream.set_option(tcp::no_delay(true));
            self->mClient.set_option(tcp::no_delay(true));
            self->pump(true);
            self->pump(false);
        });
    }

private:
    // Passes what one side sends to the other once it is due: client to server (`upward`) after
    // the round trip's delay, server to client once the shared link has carried it.
    void pump(bool upward) {
        auto self = shared_from_this();
        char* bytes = upward ? mUpBytes : mDownBytes;
        const size_t capacity = upward ? sizeof mUpBytes : sizeof mDownBytes;
        tcp::socket& from = upward ? mClient : mUpstream;
        using Error = boost::system::error_code;
        from.async_read_some(asio::buffer(bytes, capacity), [self, upward, bytes](Error e, size_t n) {
            if (e) return self->close();
            asio::steady_timer& due = upward ? self->mUp : self->mDown;
            if (upward) due.expires_after(self->mLink.delay);
            else due.expires_at(self->mLink.send(n));
            due.async_wait([self, upward, bytes, n](Error waited) {
                if (waited) return self->close();
                asio::async_write(upward ? self->mUpstream : self->mClient, asio::buffer(bytes, n),
                                  [self, upward](Error written, size_t) {
                                      if (written) return self->close();
                                      self->pump(upward);
                                  });
            });
        });
    }
    void close() {
        boost::system::error_code ignored;
        mClient.close(ignored);
        mUpstream.close(ignored);
        mUp.cancel();
        mDown.cancel();
    }

    tcp::socket mClient, mUpstream;
    asio::steady_timer mUp, mDown;
    Link& mLink;
    char mUpBytes[16 * 1024];
    char mDownBytes[64 * 1024];
};

void accept(asio::io_context& io, tcp::acceptor& acceptor, const tcp::endpoint& upstream, Link& link) {
    acceptor.async_accept([&](boost::system::error_code e, tcp::socket socket) {
        if (!acceptor.is_open()) return;
        if (!e) std::make_shared<Pair>(io, std::move(socket), link)->start(upstream);
        accept(io, acceptor, upstream, link);
    });
}

[[noreturn]] void usage(const char* why) {
    std::fprintf(stderr,
                 "vdiso_link_proxy: %s\nusage: vdiso_link_proxy --upstream PORT [--delay-ms N] "
                 "[--rate-mbit M] [--lifetime S]\n",
                 why);
    std::exit(2);
}

}  // namespace

int main(int argc, char** argv) {
    int upstreamPort = 0;
    double delayMs = 0, rateMbit = 0, lifetime = 3600;
    for (int i = 1; i < argc; ++i) {
        const std::string a = argv[i];
        if (i + 1 >= argc) usage(("no value after " + a).c_str());
        char* end = nullptr;
        const double v = std::strtod(argv[++i], &end);
        if (*end || v < 0) usage(("not a number >= 0: " + a + " " + argv[i]).c_str());
        if (a == "--upstream") upstreamPort = int(v);
        else if (a == "--delay-ms") delayMs = v;
        else if (a == "--rate-mbit") rateMbit = v;
        else if (a == "--lifetime") lifetime = v;
        else usage(("unknown option " + a).c_str());
    }
    if (upstreamPort <= 0 || upstreamPort > 65535) usage("--upstream PORT is required (1-65535)");

    asio::io_context io;
    Link link;
    link.delay = std::chrono::milliseconds(int64_t(delayMs));
    link.bytesPerSecond = rateMbit * 1e6 / 8;
    const tcp::endpoint upstream(asio::ip::make_address("127.0.0.1"), uint16_t(upstreamPort));
    tcp::acceptor acceptor(io, tcp::endpoint(asio::ip::make_address("127.0.0.1"), 0));
    std::printf("PORT %d\n", int(acceptor.local_endpoint().port()));
    std::fflush(stdout);
    accept(io, acceptor, upstream, link);

    auto stop = [&] { io.stop(); };
    asio::signal_set signals(io, SIGINT, SIGTERM);
    signals.async_wait([&](boost::system::error_code, int) { stop(); });
    asio::steady_timer lifetimeTimer(io, std::chrono::milliseconds(int64_t(lifetime * 1000)));
    lifetimeTimer.async_wait([&](boost::system::error_code e) {
        if (!e) stop();
    });
    // Stdin a pipe: its end (the caller gone) ends the proxy.
    std::unique_ptr<asio::posix::stream_descriptor> in;
    char sink[256];
    struct stat st {};
    if (fstat(0, &st) == 0 && S_ISFIFO(st.st_mode)) {
        in = std::make_unique<asio::posix::stream_descriptor>(io, ::dup(0));
        std::function<void()> watch = [&] {
            in->async_read_some(asio::buffer(sink), [&](boost::system::error_code e, size_t) {
                if (e) return stop();
                watch();
            });
        };
        watch();
    }
    io.run();
    return 0;
}
