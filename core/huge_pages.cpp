#include "core/huge_pages.h"

#include <cstdint>
#include <new>

#include <sys/mman.h>

namespace vdiso {

void* mapHugePages(size_t bytes) {
    void* p = ::mmap(nullptr, bytes, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
    if (p == MAP_FAILED) throw std::bad_alloc();
    // The head stays in ordinary pages: a buffer reserved large and filled little (a view's
    // mesh arrays, reserved for a couple of triangles a pixel) zeroes only the 4 KB pages it
    // writes, where its first huge page zeroed 2 MB of each array every frame (a tenth of a
    // distant CT frame). What lies past the first huge page boundary beyond kHugePageBytes is
    // marked.
    if (bytes > kHugePageBytes) adviseHugePages(static_cast<unsigned char*>(p) + kHugePageBytes, bytes - kHugePageBytes);
    return p;
}

void unmapHugePages(void* p, size_t bytes) noexcept { ::munmap(p, bytes); }

void adviseHugePages(void* p, size_t bytes) noexcept {
    const uintptr_t begin = reinterpret_cast<uintptr_t>(p), end = begin + bytes;
    const uintptr_t huge = (begin + kHugePageBytes - 1) & ~uintptr_t(kHugePageBytes - 1);
    if (huge < end) ::madvise(reinterpret_cast<void*>(huge), end - huge, MADV_HUGEPAGE);
}

}  // namespace vdiso
