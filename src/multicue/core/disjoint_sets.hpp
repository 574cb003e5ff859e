#pragma once
/// \file Union-find over dense indices, shared by the clustering algorithms and the simulator.
/// Internal helper: not part of the stable API.

#include <cstddef>

#include "multicue/core/types.hpp"

namespace multicue::detail {

/// Disjoint sets of the indices [0, n). The representative of a set is always its smallest index,
/// so the sets and their representatives do not depend on the order of the unions.
class DisjointSets {
  public:
    explicit DisjointSets(std::size_t n) : parent_(n) {
        for (std::size_t i = 0; i < n; ++i) parent_[i] = static_cast<Index>(i);
    }

    /// Representative (smallest index) of the set holding i.
    Index Find(Index i) {
        while (parent_[i] != i) {
            parent_[i] = parent_[parent_[i]];  // path halving keeps later finds short
            i = parent_[i];
        }
        return i;
    }

    /// Joins the sets holding a and b.
    void Unite(Index a, Index b) {
        a = Find(a);
        b = Find(b);
        if (a < b) {
            parent_[b] = a;
        } else if (b < a) {
            parent_[a] = b;
        }
    }

  private:
    Indices parent_;
};

}  // namespace multicue::detail
