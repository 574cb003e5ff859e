#include "multicue/core/parallel.hpp"

#include <fmt/format.h>

namespace multicue {

int ResolveThreadCount(int num_threads) {
    if (num_threads < 0) {
        throw InvalidArgument(
            fmt::format("num_threads must be >= 0 (0 = all cores), got {}", num_threads));
    }
    if (num_threads == 0) return tbb::this_task_arena::max_concurrency();
    return num_threads;
}

}  // namespace multicue
