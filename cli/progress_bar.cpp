#include "cli/progress_bar.h"

#include <algorithm>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <cstring>
#include <memory>

#include <unistd.h>

#include "core/interrupt.h"
#include "io/error.h"

namespace vdiso::cli {

namespace {

// The library's long loops poll the same flag (core/interrupt.h).
void onInterrupt(int) { requestInterrupt(); }

struct BarState {
    std::string label;
    double bytesTotal;
    bool draw;
    std::chrono::steady_clock::time_point start = std::chrono::steady_clock::now();
    std::chrono::steady_clock::time_point lastDraw{};
};

}  // namespace

void installInterruptHandler() {
    struct sigaction sa = {};
    sa.sa_handler = onInterrupt;
    sigemptyset(&sa.sa_mask);
    sigaction(SIGINT, &sa, nullptr);
    sigaction(SIGTERM, &sa, nullptr);
}

ProgressFn progressBar(const std::string& label, double bytesTotal, bool quiet) {
    auto state = std::make_shared<BarState>();
    state->label = label;
    state->bytesTotal = bytesTotal;
    state->draw = !quiet && ::isatty(STDERR_FILENO);
    return [state](double fraction) {
        if (interruptRequested()) {
            if (state->draw) std::fputs("\n", stderr);
            throw Interrupted(state->label + ": interrupted");
        }
        if (!state->draw) return;
        // The bar's width and percentage come from the fraction: keep it in [0, 1] whatever a
        // caller passes (NaN as 0), so that no int conversion is undefined or huge.
        fraction = fraction >= 0 ? std::min(fraction, 1.0) : 0.0;
        const auto now = std::chrono::steady_clock::now();
        if (fraction < 1.0 && now - state->lastDraw < std::chrono::milliseconds(100)) return;
        state->lastDraw = now;
        constexpr int kWidth = 40;
        const int filled = int(fraction * kWidth + 0.5);
        const double seconds = std::chrono::duration<double>(now - state->start).count();
        char rate[48] = "";
        if (state->bytesTotal > 0 && seconds > 0)
            std::snprintf(rate, sizeof rate, "  %.0f MB/s",
                          fraction * state->bytesTotal / seconds / 1e6);
        std::fprintf(stderr, "\r%s [%.*s%*s] %3d%%  %.1f s%s", state->label.c_str(), filled,
                     "########################################", kWidth - filled, "",
                     int(fraction * 100 + 0.5), seconds, rate);
        if (fraction >= 1.0) std::fputs("\n", stderr);
        std::fflush(stderr);
    };
}

}  // namespace vdiso::cli
