// Large buffers mapped straight from the kernel and marked for transparent huge pages past
// their first 2-4 MB (madvise MADV_HUGEPAGE, a hint: without THP they are ordinary pages). A
// buffer written once from start to end, as a brick cache chunk or an extraction's mesh arrays
// are, then takes one page fault per 2 MB instead of one per 4 KB: on a CT's full extraction the
// faults of the fresh mesh arrays were about a tenth of the time, and on two threads they
// serialise in the kernel. The head in ordinary pages keeps a buffer reserved large and filled
// little from zeroing a whole huge page for its first bytes.
#pragma once

#include <cstddef>

namespace vdiso {

// Buffers of at least this many bytes are worth mapping this way.
constexpr size_t kHugePageBytes = size_t(2) << 20;

// Zeroed, page-aligned memory of `bytes` (> 0) bytes; throws std::bad_alloc when the kernel
// has none.
void* mapHugePages(size_t bytes);
// Returns what mapHugePages(bytes) gave.
void unmapHugePages(void* p, size_t bytes) noexcept;

}  // namespace vdiso
