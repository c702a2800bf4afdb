#pragma once
// A fixed-size array of a trivially copyable type, all bytes zero, whose pages are left for the
// kernel to supply on first touch: calloc takes a large block straight from mmap, whose pages are
// zero already, and skips the memset a value-initialised std::vector does. A 1024 x 1024 film
// (64 MB) took 170 ms to value-initialise on the project's 2-core VM, every page faulted in by
// the job's thread before its first tile could start; now each page faults in when a render
// thread first adds to it, spread over the first pass and across the threads. (C++20: calloc
// creates the array's implicit-lifetime objects, with the zero bytes as their values.)
// Alignment up to 64 (a cache line) is kept by over-allocating and aligning the start; a block of
// 2 MB or more starts on a 2 MB boundary (2 MB more address space, never touched), so every one
// of its 2 MB pages can be a huge page: calloc's own start is only page-aligned, which left a
// 4 MB block (a 256 x 256 film) one huge page and 512 small ones.
// T need not be trivially default-constructible: a trivially copyable type is an implicit-lifetime
// type, and its zero bytes are its value (a Vec3d of zeros).
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <new>
#include <sys/mman.h>
#include <type_traits>
#include <utility>

namespace omega {

template <class T>
class ZeroedArray {
    static_assert(std::is_trivially_copyable_v<T>);
    static_assert(alignof(T) <= 64);
    static constexpr size_t kHuge = size_t(2) << 20;

public:
    ZeroedArray() = default;
    explicit ZeroedArray(size_t n) : n_(n) {
        if (n == 0) return;
        if (n > (SIZE_MAX - kHuge) / sizeof(T)) throw std::bad_alloc();
        const size_t bytes = n * sizeof(T);
        const size_t align = bytes >= kHuge ? kHuge : alignof(T);
        raw_ = std::calloc(bytes + align, 1);
        if (!raw_) throw std::bad_alloc();
        const uintptr_t a = (reinterpret_cast<uintptr_t>(raw_) + align - 1) & ~uintptr_t(align - 1);
        data_ = reinterpret_cast<T*>(a);
        huge_pages(data_, bytes);
    }
    ZeroedArray(const ZeroedArray& o) : ZeroedArray(o.n_) {
        if (n_) std::memcpy(data_, o.data_, n_ * sizeof(T));
    }
    ZeroedArray(ZeroedArray&& o) noexcept
        : raw_(std::exchange(o.raw_, nullptr)), data_(std::exchange(o.data_, nullptr)), n_(std::exchange(o.n_, 0)) {}
    ZeroedArray& operator=(ZeroedArray o) noexcept {
        std::swap(raw_, o.raw_);
        std::swap(data_, o.data_);
        std::swap(n_, o.n_);
        return *this;
    }
    ~ZeroedArray() { std::free(raw_); }

    size_t size() const { return n_; }
    bool empty() const { return n_ == 0; }
    T* data() { return data_; }
    const T* data() const { return data_; }
    T& operator[](size_t i) { return data_[i]; }
    const T& operator[](size_t i) const { return data_[i]; }
    T* begin() { return data_; }
    T* end() { return data_ + n_; }
    const T* begin() const { return data_; }
    const T* end() const { return data_ + n_; }

private:
    // Transparent huge pages for the block's whole 2 MB pages, where the kernel offers them on
    // request (Debian's default, `madvise`): a 64 MB film then faults in 32 times, not 16384.
    // Only advice: where it is refused, the block keeps its small pages.
    static void huge_pages(void* p, size_t bytes) {
        const uintptr_t b = (reinterpret_cast<uintptr_t>(p) + kHuge - 1) & ~(kHuge - 1);
        const uintptr_t e = (reinterpret_cast<uintptr_t>(p) + bytes) & ~(kHuge - 1);
        if (e > b) (void)madvise(reinterpret_cast<void*>(b), e - b, MADV_HUGEPAGE);
    }

    void* raw_ = nullptr;
    T* data_ = nullptr;
    size_t n_ = 0;
};

}  // namespace omega
