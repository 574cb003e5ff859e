#pragma once
/// \file The order in which to hand tasks of unequal cost to a parallel loop.

#include <algorithm>
#include <cstddef>
#include <vector>

namespace multicue {

/// The positions [0, n) by decreasing size(i), equal sizes by position: a loop that takes its
/// tasks in this order does not start a long one last, which would leave one thread working
/// alone at its end. Reordering the tasks of a loop that writes per task never changes results.
template <typename Size>
std::vector<std::size_t> LargestFirst(std::size_t n, Size&& size) {
    std::vector<std::size_t> order(n);
    for (std::size_t k = 0; k < n; ++k) order[k] = k;
    std::stable_sort(order.begin(), order.end(),
                     [&](std::size_t a, std::size_t b) { return size(a) > size(b); });
    return order;
}

}  // namespace multicue
