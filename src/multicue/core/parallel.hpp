#pragma once
/// \file Parallel helpers over TBB. The thread count is a parameter of each call (0 = all cores),
/// applied locally through a task arena, never process-wide.

#include <algorithm>
#include <cstddef>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include "multicue/core/exceptions.hpp"
#include "multicue/core/types.hpp"

#include <functional>
#include <vector>

namespace multicue {

namespace detail {
/// Runs chunk(0) ... chunk(count - 1) on `count` threads (the calling one and count - 1 new
/// std::threads), joins them and rethrows the first exception. ThreadSanitizer builds
/// (MULTICUE_TSAN_PLAIN_THREADS, cmake/MulticueSanitize.cmake) run the parallel loops this way:
/// Debian's TBB is not built with ThreadSanitizer, so the order its scheduler guarantees between
/// a loop and its tasks, and the reuse of its task objects, are invisible to the sanitizer, while
/// thread creation and joining are seen. The races the sanitizer then reports are multicue's.
void RunOnThreads(std::size_t count, const std::function<void(std::size_t)>& chunk);
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
#if defined(MULTICUE_TSAN_PLAIN_THREADS)
    const auto chunks =
        std::min<std::size_t>(static_cast<std::size_t>(threads), (n + grain - 1) / grain);
    detail::RunOnThreads(chunks,
                         [&](std::size_t c) { body(n * c / chunks, n * (c + 1) / chunks); });
#else
    auto loop = [&] {
        tbb::parallel_for(
            tbb::blocked_range<std::size_t>(0, n, grain),
            [&](const tbb::blocked_range<std::size_t>& r) { body(r.begin(), r.end()); });
    };
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
#endif
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

/// Runs first() and second() at the same time when num_threads allows, else one after the other
/// (first() first). They must not write the same data.
template <typename First, typename Second>
void ParallelInvoke(int num_threads, First&& first, Second&& second) {
    ParallelFor(
        2, num_threads, [&](std::size_t k) { k == 0 ? first() : second(); }, 1);
}

/// The i in [0, n) for which keep(i) holds, ascending, whatever the thread count: blocks of
/// indices are selected in parallel and joined in order.
template <typename Keep>
Indices ParallelSelect(std::size_t n, int num_threads, Keep&& keep, std::size_t grain = 16384) {
    const std::size_t blocks = std::max<std::size_t>(1, (n + grain - 1) / grain);
    std::vector<Indices> kept(blocks);
    ParallelFor(
        blocks, num_threads,
        [&](std::size_t b) {
            const std::size_t end = std::min(n, (b + 1) * grain);
            for (std::size_t i = b * grain; i < end; ++i) {
                if (keep(i)) kept[b].push_back(static_cast<Index>(i));
            }
        },
        1);
    std::size_t total = 0;
    for (const auto& k : kept) total += k.size();
    Indices out;
    out.reserve(total);
    for (const auto& k : kept) out.insert(out.end(), k.begin(), k.end());
    return out;
}

}  // namespace multicue
