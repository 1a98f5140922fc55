#include "released.h"

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <exception>
#include <mutex>
#include <optional>
#include <thread>

#include "core/interrupt.h"

namespace vdiso::py {

namespace pyb = pybind11;

void runReleased(const std::function<void(const ProgressFn&)>& work, pyb::object progress, double total) {
    std::mutex mutex;
    std::condition_variable cv;
    bool done = false;
    std::exception_ptr failure;
    std::atomic<double> fraction{-1.0};
    std::optional<pyb::error_already_set> pythonError;  // Ctrl-C or the callable's exception
    // The callable's exception stops this call's work alone (at its next progress report); a
    // signal (Ctrl-C) asks every loop of the library to stop (core/interrupt.h), as it does in
    // the command, and is withdrawn by the call that asked once its work has unwound. (The flag
    // is not cleared at the start: a call starting in another thread would withdraw it.)
    std::atomic<bool> stopThis{false};
    bool askedEveryone = false;
    {
        pyb::gil_scoped_release release;
        std::thread worker([&] {
            try {
                // The library's loops report progress often (every few bricks or MB): each
                // report is also where a Ctrl-C seen by the waiting thread stops the work.
                work([&](double f) {
                    fraction.store(f, std::memory_order_relaxed);
                    if (stopThis.load(std::memory_order_relaxed)) throw Interrupted("vdiso: interrupted");
                    throwIfInterrupted("vdiso");
                });
            } catch (...) {
                failure = std::current_exception();
            }
            std::lock_guard lock(mutex);
            done = true;
            cv.notify_all();
        });
        double shown = -1.0;
        for (;;) {
            {
                std::unique_lock lock(mutex);
                if (cv.wait_for(lock, std::chrono::milliseconds(50), [&] { return done; })) break;
            }
            if (pythonError) continue;  // already stopping
            pyb::gil_scoped_acquire acquire;
            bool signalled = false;
            try {
                if (PyErr_CheckSignals() != 0) {
                    signalled = true;
                    throw pyb::error_already_set();
                }
                const double f = fraction.load(std::memory_order_relaxed);
                if (!progress.is_none() && f >= 0 && f != shown) {
                    shown = f;
                    progress(f * total, total);
                }
            } catch (pyb::error_already_set& e) {
                pythonError.emplace(std::move(e));
                stopThis = true;
                if (signalled) {
                    requestInterrupt();
                    askedEveryone = true;
                }
            }
        }
        worker.join();
    }
    if (askedEveryone) clearInterrupt();
    if (pythonError) throw std::move(*pythonError);
    if (failure) std::rethrow_exception(failure);
    // The last call comes after the work is done (an output is in place): what it raises is
    // a warning, not a failure of work that did not fail.
    if (!progress.is_none()) {
        try {
            progress(total, total);
        } catch (pyb::error_already_set& e) {
            const std::string what = "vdiso: the progress callback raised on its last call, after the work was done: " +
                                     pyb::str(e.type().attr("__name__")).cast<std::string>() + ": " +
                                     pyb::str(e.value()).cast<std::string>();
            if (PyErr_WarnEx(PyExc_RuntimeWarning, what.c_str(), 1) != 0) throw pyb::error_already_set();
        }
    }
}

}  // namespace vdiso::py
