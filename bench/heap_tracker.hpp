#pragma once
/// \file Peak heap use of one call. The benchmark program replaces malloc and its relatives with
/// thin wrappers around glibc's allocator that, while tracking is on, add up the usable size of
/// every block allocated and freed (from any thread). The peak of that running sum is the most heap
/// memory the call held above what was allocated before it started. Memory a library maps without
/// malloc (mmap of files, thread stacks) is not counted, and allocations glibc makes internally
/// (strdup, reallocarray) are missed, so the figure is a slight underestimate.

#include <cstdint>

namespace multicue::bench {

/// Resets the running sum and its peak to zero and starts counting.
void StartHeapTracking();

/// Stops counting and returns the peak of the running sum [bytes].
std::int64_t StopHeapTracking();

}  // namespace multicue::bench
