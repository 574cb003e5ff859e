#pragma once
/// \file Part graphs and their connected subgraphs (thesis section 5.1.1, Figure 5.5; hash keys
/// of section 5.1.2, Figure 5.6).
///
/// The parts of an over-segmented object or scene (region growing, section 4.2.1) are the
/// vertices; two parts are adjacent when some point of one lies within `adjacency_distance` of a
/// point of the other. Every connected subgraph up to a size is enumerated exactly once with the
/// ESU algorithm (Wernicke, 2006): a subgraph is grown only from its smallest vertex, and a
/// vertex joins the extension set only when it is larger than that root and not yet adjacent to
/// the subgraph, so the order of the vertices makes every vertex set reachable by one path.
/// A subgraph's hash key is (number of parts, degree sequence within the subgraph sorted in
/// descending order): equal for isomorphic subgraphs (the converse does not hold).

#include <cstddef>
#include <cstdint>
#include <functional>
#include <span>
#include <vector>

#include "multicue/core/point_cloud.hpp"
#include "multicue/core/types.hpp"

namespace multicue {

/// Largest subgraph size a key can describe (4 bits per entry in a 64-bit key).
inline constexpr std::size_t kMaxSubgraphParts = 15;

/// Undirected simple graph over parts 0 .. n-1.
class PartGraph {
  public:
    PartGraph() = default;
    explicit PartGraph(std::size_t num_parts);
    /// Adds the edge a - b (ignored if present). Throws InvalidArgument for a == b or an index
    /// out of range.
    void AddEdge(std::uint32_t a, std::uint32_t b);
    bool Adjacent(std::uint32_t a, std::uint32_t b) const { return matrix_[a * n_ + b] != 0; }
    std::size_t size() const { return n_; }
    std::size_t num_edges() const;
    /// Neighbours of `v`, ascending.
    const std::vector<std::uint32_t>& Neighbours(std::uint32_t v) const { return adj_[v]; }

  private:
    std::size_t n_ = 0;
    std::vector<std::vector<std::uint32_t>> adj_;
    std::vector<std::uint8_t> matrix_;
};

struct PartGraphParams {
    float adjacency_distance = 0.015f;  ///< parts closer than this are adjacent [m]; > 0
};

/// Builds the part graph of `parts` (indices into `cloud`; non-finite points are ignored).
/// Points are hashed into cells of adjacency_distance; only parts sharing neighbouring cells are
/// compared point by point. Throws InvalidArgument for a bad distance or an index out of range.
PartGraph BuildPartGraph(const PointCloud& cloud, const std::vector<Indices>& parts,
                         const PartGraphParams& params = {});

/// Called once per connected subgraph with its vertices (the root first, then in the order they
/// were added). Return false to stop the enumeration.
using SubgraphVisitor = std::function<bool(std::span<const std::uint32_t>)>;

/// Enumerates every connected subgraph of 1 .. max_parts vertices exactly once (ESU). Roots are
/// taken in the order of `root_order` (a permutation of the vertices; empty = ascending), which
/// only changes the order of the visits, not the set. Returns the number of subgraphs visited.
/// Throws InvalidArgument if max_parts is 0 or above kMaxSubgraphParts, or root_order is not a
/// permutation.
std::size_t EnumerateConnectedSubgraphs(const PartGraph& graph, std::size_t max_parts,
                                        const SubgraphVisitor& visit,
                                        std::span<const std::uint32_t> root_order = {});

/// Hash key of a subgraph: bits 60-63 the number of parts, then 4 bits per degree in
/// descending order (highest degree in bits 56-59).
std::uint64_t SubgraphKey(const PartGraph& graph, std::span<const std::uint32_t> vertices);
/// Number of parts encoded in a key.
std::size_t KeyParts(std::uint64_t key);
/// Sorted (descending) degree sequence encoded in a key.
std::vector<int> KeyDegrees(std::uint64_t key);

}  // namespace multicue
