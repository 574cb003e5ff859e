#include "multicue/core/parallel.hpp"

#include <algorithm>
#include <exception>
#include <mutex>
#include <thread>
#include <vector>

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

namespace detail {

void RunOnThreads(std::size_t count, const std::function<void(std::size_t)>& chunk) {
    std::exception_ptr error;
    std::mutex error_mutex;
    auto run = [&](std::size_t c) {
        try {
            chunk(c);
        } catch (...) {
            const std::lock_guard<std::mutex> lock(error_mutex);
            if (!error) error = std::current_exception();
        }
    };
    std::vector<std::thread> threads;
    threads.reserve(count > 0 ? count - 1 : 0);
    for (std::size_t c = 1; c < count; ++c) threads.emplace_back(run, c);
    if (count > 0) run(0);
    for (auto& t : threads) t.join();
    if (error) std::rethrow_exception(error);
}

}  // namespace detail

}  // namespace multicue
