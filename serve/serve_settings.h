// What a server's options (serve/serve_options.h) make, before any connection: the settings
// every viewer's frames run with, and how many frames may extract at once.
#pragma once

#include "serve/serve_options.h"
#include "serve/store_catalog.h"
#include "serve/viewer_session.h"

namespace vdiso::serve {

// A frame looks 8 bricks ahead with 2 readers in all (at least one a strip), so that a frame's
// threads stay near the cores it runs on; over a network, as far as vdiso extract does
// (RemoteReadAhead, core/extract/brick_look_ahead.h).
SessionSettings sessionSettings(const ServeOptions& options, StoreCatalog& stores);

// Frames that may extract at once: the machine's cores (four a core for a store at a URL, at
// least 2), and no more than every store's cache holds the pins of: each frame needs
// frameCacheBricks (cache/cache_plan.h, the rule vdiso extract plans by).
// Throws CacheBudgetError naming the store whose cache cannot hold one frame.
int frameSlots(StoreCatalog& stores, const SessionSettings& settings);

}  // namespace vdiso::serve
