// Running library work from Python: on a worker thread, the GIL released, while the calling
// thread waits and, every 50 ms, takes the GIL to hand progress to a Python callable and to let
// Python see Ctrl-C. An exception from the callable stops this call's work at its next progress
// report; a KeyboardInterrupt (any exception a signal handler raises) asks every loop of the
// library to stop (core/interrupt.h), as Ctrl-C does in the command. Either way the call waits
// for its work to unwind (its outputs removed) and raises it; work in other threads' calls goes
// on unless a signal stopped it.
#pragma once

#include <pybind11/pybind11.h>

#include <functional>

#include "core/progress.h"

namespace vdiso::py {

// Runs work(progress) as above; `progress`: None or callable(done, total), called with
// done = fraction * total. Rethrows what work throws.
void runReleased(const std::function<void(const ProgressFn&)>& work, pybind11::object progress = pybind11::none(),
                 double total = 1.0);

}  // namespace vdiso::py
