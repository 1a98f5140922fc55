// Names the calling thread for `top -H`, gdb and /proc/self/task/*/comm, so that each of vdiso's
// threads says what it does: "vdiso-frame" (a served frame's worker), "vdiso-reader" (a
// look-ahead's reader), "vdiso-strip" (an image strip's traversal), "vdiso-transfer" (a remote
// session's requests), "vdiso-index" (a remote index's background parts), "vdiso-cache" (a disk
// cache's writer). Linux shows the first 15 characters. Never fails: a name is only a help.
#pragma once

#include <pthread.h>

namespace vdiso {

inline void nameThisThread(const char* name) { pthread_setname_np(pthread_self(), name); }

}  // namespace vdiso
