#include "heap_tracker.hpp"

#include <malloc.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <cstddef>
#include <cstdlib>

// glibc's own entry points, which the replacements below forward to.
extern "C" {
void* __libc_malloc(std::size_t size);
void __libc_free(void* ptr);
void* __libc_calloc(std::size_t count, std::size_t size);
void* __libc_realloc(void* ptr, std::size_t size);
void* __libc_memalign(std::size_t alignment, std::size_t size);
}

namespace {

// Constant-initialized, so they are usable by allocations made before main and by static
// constructors of the shared libraries.
std::atomic<bool> g_tracking{false};
std::atomic<std::int64_t> g_current{0};
std::atomic<std::int64_t> g_peak{0};

void CountAllocated(void* ptr) {
    if (ptr == nullptr || !g_tracking.load(std::memory_order_relaxed)) return;
    const auto bytes = static_cast<std::int64_t>(malloc_usable_size(ptr));
    const std::int64_t now = g_current.fetch_add(bytes, std::memory_order_relaxed) + bytes;
    std::int64_t peak = g_peak.load(std::memory_order_relaxed);
    while (now > peak && !g_peak.compare_exchange_weak(peak, now, std::memory_order_relaxed)) {
    }
}

void CountFreed(void* ptr) {
    if (ptr == nullptr || !g_tracking.load(std::memory_order_relaxed)) return;
    g_current.fetch_sub(static_cast<std::int64_t>(malloc_usable_size(ptr)),
                        std::memory_order_relaxed);
}

bool IsPowerOfTwo(std::size_t v) { return v != 0 && (v & (v - 1)) == 0; }

std::size_t PageSize() { return static_cast<std::size_t>(sysconf(_SC_PAGESIZE)); }

}  // namespace

extern "C" {

void* malloc(std::size_t size) noexcept {
    void* ptr = __libc_malloc(size);
    CountAllocated(ptr);
    return ptr;
}

void free(void* ptr) noexcept {
    CountFreed(ptr);
    __libc_free(ptr);
}

void* calloc(std::size_t count, std::size_t size) noexcept {
    void* ptr = __libc_calloc(count, size);
    CountAllocated(ptr);
    return ptr;
}

void* realloc(void* ptr, std::size_t size) noexcept {
    const std::size_t old_bytes = ptr != nullptr ? malloc_usable_size(ptr) : 0;
    void* result = __libc_realloc(ptr, size);
    // On failure (null result with size > 0) the old block is still allocated.
    if (result != nullptr || size == 0) {
        if (g_tracking.load(std::memory_order_relaxed)) {
            g_current.fetch_sub(static_cast<std::int64_t>(old_bytes), std::memory_order_relaxed);
        }
        CountAllocated(result);
    }
    return result;
}

void* memalign(std::size_t alignment, std::size_t size) noexcept {
    void* ptr = __libc_memalign(alignment, size);
    CountAllocated(ptr);
    return ptr;
}

void* aligned_alloc(std::size_t alignment, std::size_t size) noexcept {
    return memalign(alignment, size);
}

int posix_memalign(void** out, std::size_t alignment, std::size_t size) noexcept {
    if (!IsPowerOfTwo(alignment) || alignment % sizeof(void*) != 0) return EINVAL;
    void* ptr = memalign(alignment, size);
    if (ptr == nullptr) return ENOMEM;
    *out = ptr;
    return 0;
}

void* valloc(std::size_t size) noexcept { return memalign(PageSize(), size); }

void* pvalloc(std::size_t size) noexcept {
    const std::size_t page = PageSize();
    return memalign(page, (size + page - 1) / page * page);
}

}  // extern "C"

namespace multicue::bench {

void StartHeapTracking() {
    g_tracking.store(false);
    g_current.store(0);
    g_peak.store(0);
    g_tracking.store(true);
}

std::int64_t StopHeapTracking() {
    g_tracking.store(false);
    return g_peak.load();
}

}  // namespace multicue::bench
