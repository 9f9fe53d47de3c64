// Cache-line aligned std::vector storage.
#pragma once
#include <cstddef>
#include <new>
#include <vector>

namespace qdem {

// std::vector storage aligned to cache lines: for arrays read and written
// with aligned vector loads and stores (the element kernel's tet blocks and
// padded force buffers), whatever the element type's own alignment.
template <class T, std::size_t Align = 64>
struct AlignedAllocator {
    using value_type = T;
    AlignedAllocator() = default;
    template <class U>
    AlignedAllocator(const AlignedAllocator<U, Align>&) {}
    template <class U>
    struct rebind {
        using other = AlignedAllocator<U, Align>;
    };
    T* allocate(std::size_t n) { return static_cast<T*>(::operator new(n * sizeof(T), std::align_val_t(Align))); }
    void deallocate(T* p, std::size_t) { ::operator delete(p, std::align_val_t(Align)); }
    bool operator==(const AlignedAllocator&) const { return true; }
    bool operator!=(const AlignedAllocator&) const { return false; }
};

template <class T>
using AlignedVector = std::vector<T, AlignedAllocator<T>>;

}  // namespace qdem
