// Progress reporting for long operations: called with the fraction done (0..1), from one
// thread, every few bricks or slabs. A callback may throw to interrupt the operation; the
// operation then cleans up (no partial output) and lets the exception through.
#pragma once

#include <functional>

namespace vdiso {

using ProgressFn = std::function<void(double fractionDone)>;

}  // namespace vdiso
