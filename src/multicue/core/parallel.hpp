#pragma once
/// \file Parallel helpers over TBB. The thread count is a parameter of each call (0 = all cores),
/// applied locally through a task arena, never process-wide.

#include <cstddef>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include "multicue/core/exceptions.hpp"

#if defined(MULTICUE_TSAN_ANNOTATIONS)
#include <sanitizer/tsan_interface.h>
#endif

namespace multicue {

namespace detail {
// ThreadSanitizer sees no order between a TBB task and the thread that spawned or joined it, since
// TBB's scheduler is not instrumented (Debian's build). In a ThreadSanitizer build
// (MULTICUE_TSAN_ANNOTATIONS, cmake/MulticueSanitize.cmake) these calls state the order that
// tbb::parallel_for guarantees: all before the loop happens before every task, every task before
// all after it. Elsewhere they are empty.
#if defined(MULTICUE_TSAN_ANNOTATIONS)
inline char tsan_fork_token, tsan_join_token;
inline void TsanFork() { __tsan_release(&tsan_fork_token); }
inline void TsanTaskStart() { __tsan_acquire(&tsan_fork_token); }
inline void TsanTaskEnd() { __tsan_release(&tsan_join_token); }
inline void TsanJoin() { __tsan_acquire(&tsan_join_token); }
#else
inline void TsanFork() {}
inline void TsanTaskStart() {}
inline void TsanTaskEnd() {}
inline void TsanJoin() {}
#endif
}  // namespace detail

/// Number of threads `num_threads` stands for (0 = all cores). Throws on negative values.
int ResolveThreadCount(int num_threads);

/// Threads an arena can really use for `num_threads`: ResolveThreadCount capped at the cores
/// present (asking TBB for more only makes it print a warning). Results never depend on it.
int ArenaThreadCount(int num_threads);

/// Calls body(begin, end) over disjoint chunks covering [0, n), with at most `num_threads` threads.
/// Results must not depend on the chunking: write per index, never accumulate across chunks.
template <typename Body>
void ParallelForChunks(std::size_t n, int num_threads, Body&& body, std::size_t grain = 1024) {
    if (n == 0) return;
    const int threads = ArenaThreadCount(num_threads);
    if (threads == 1 || n <= grain) {
        body(std::size_t{0}, n);
        return;
    }
    auto loop = [&] {
        tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, grain),
                          [&](const tbb::blocked_range<std::size_t>& r) {
                              detail::TsanTaskStart();
                              body(r.begin(), r.end());
                              detail::TsanTaskEnd();
                          });
    };
    detail::TsanFork();
    // Nested in a parallel loop of at most `threads` threads (objects in parallel, each with
    // loops of its own): the inner loop runs in that loop's arena, so that its threads help
    // wherever work is left, and in isolation, so that a thread waiting for it takes no outer
    // task that could reuse its thread-local buffers.
    if (tbb::this_task_arena::current_thread_index() != tbb::task_arena::not_initialized &&
        tbb::this_task_arena::max_concurrency() <= threads) {
        tbb::this_task_arena::isolate(loop);
    } else {
        tbb::task_arena arena(threads);
        arena.execute(loop);
    }
    detail::TsanJoin();
}

/// Calls body(i) for every i in [0, n).
template <typename Body>
void ParallelFor(std::size_t n, int num_threads, Body&& body, std::size_t grain = 1024) {
    ParallelForChunks(
        n, num_threads,
        [&](std::size_t begin, std::size_t end) {
            for (std::size_t i = begin; i < end; ++i) body(i);
        },
        grain);
}

}  // namespace multicue
