#include "multicue/core/parallel.hpp"

#include <algorithm>

#include <fmt/format.h>
#include <tbb/info.h>

namespace multicue {

int ResolveThreadCount(int num_threads) {
    if (num_threads < 0) {
        throw InvalidArgument(
            fmt::format("num_threads must be >= 0 (0 = all cores), got {}", num_threads));
    }
    if (num_threads == 0) return tbb::this_task_arena::max_concurrency();
    return num_threads;
}

int ArenaThreadCount(int num_threads) {
    return std::min(ResolveThreadCount(num_threads), tbb::info::default_concurrency());
}

}  // namespace multicue
