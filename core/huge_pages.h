// Large buffers mapped straight from the kernel and marked for transparent huge pages past
// their first 2-4 MB (madvise MADV_HUGEPAGE, a hint: without THP they are ordinary pages). A
// buffer written once from start to end, as a brick cache chunk or an extraction's mesh arrays
// are, then takes one page fault per 2 MB instead of one per 4 KB: on a CT's full extraction the
// faults of the fresh mesh arrays were about a tenth of the time, and on two threads they
// serialise in the kernel. The head in ordinary pages keeps a buffer reserved large and filled
// little from zeroing a whole huge page for its first bytes.
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <new>
#include <type_traits>
#include <utility>

namespace vdiso {

// Buffers of at least this many bytes are worth mapping this way.
constexpr size_t kHugePageBytes = size_t(2) << 20;

// Zeroed, page-aligned memory of `bytes` (> 0) bytes; throws std::bad_alloc when the kernel
// has none.
void* mapHugePages(size_t bytes);
// Returns what mapHugePages(bytes) gave.
void unmapHugePages(void* p, size_t bytes) noexcept;
// Marks the whole huge pages within [p, p + bytes) of an anonymous mapping for transparent huge
// pages (a hint). For memory that is written whole and read in scattered rows, as a
// conversion's slices are: a row of a 2048-wide u16 slice is a 4 KB page of its own.
void adviseHugePages(void* p, size_t bytes) noexcept;

// A std::allocator whose value-less construct leaves the element uninitialized, so that
// resize() does not zero what is written next anyway. The parallel merge of a full
// extraction resizes the whole mesh and fills it from several threads: a zeroing resize was a
// serial pass over it (page faults included) that took a third of the time on two threads.
// Arrays of kHugePageBytes and more are mapped by mapHugePages.
template <class T>
struct UninitializedAllocator : std::allocator<T> {
    template <class U>
    struct rebind {
        using other = UninitializedAllocator<U>;
    };
    UninitializedAllocator() = default;
    template <class U>
    UninitializedAllocator(const UninitializedAllocator<U>&) noexcept {}
    T* allocate(size_t n) {
        if (n > SIZE_MAX / sizeof(T)) throw std::bad_array_new_length();
        if (n * sizeof(T) < kHugePageBytes) return std::allocator<T>::allocate(n);
        return static_cast<T*>(mapHugePages(n * sizeof(T)));
    }
    void deallocate(T* p, size_t n) noexcept {
        if (n * sizeof(T) < kHugePageBytes) return std::allocator<T>::deallocate(p, n);
        unmapHugePages(p, n * sizeof(T));
    }
    template <class U>
    void construct(U* p) noexcept(std::is_nothrow_default_constructible_v<U>) {
        ::new (static_cast<void*>(p)) U;
    }
    template <class U, class... Args>
    void construct(U* p, Args&&... args) {
        ::new (static_cast<void*>(p)) U(std::forward<Args>(args)...);
    }
};

}  // namespace vdiso
