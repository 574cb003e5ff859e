#include "multicue/recognition/part_graph.hpp"

#include <algorithm>
#include <cmath>
#include <string>
#include <unordered_map>

#include "multicue/core/exceptions.hpp"

namespace multicue {

PartGraph::PartGraph(std::size_t num_parts)
    : n_(num_parts), adj_(num_parts), matrix_(num_parts * num_parts, 0) {}

void PartGraph::AddEdge(std::uint32_t a, std::uint32_t b) {
    if (a >= n_ || b >= n_) throw InvalidArgument("part graph: edge vertex out of range");
    if (a == b) throw InvalidArgument("part graph: self loop");
    if (matrix_[a * n_ + b]) return;
    matrix_[a * n_ + b] = matrix_[b * n_ + a] = 1;
    adj_[a].insert(std::lower_bound(adj_[a].begin(), adj_[a].end(), b), b);
    adj_[b].insert(std::lower_bound(adj_[b].begin(), adj_[b].end(), a), a);
}

std::size_t PartGraph::num_edges() const {
    std::size_t e = 0;
    for (const auto& a : adj_) e += a.size();
    return e / 2;
}

namespace {

std::uint64_t CellKey(const Eigen::Vector3i& c) {
    const auto u = [](int v) { return static_cast<std::uint64_t>(v + (1 << 20)) & 0x1fffffu; };
    return (u(c.x()) << 42) | (u(c.y()) << 21) | u(c.z());
}

struct CellEntry {
    std::uint32_t part;
    std::uint32_t point;
};

// The entries [begin, end) of a cell that belong to one part.
struct PartRun {
    std::uint32_t part;
    std::uint32_t begin, end;
};

}  // namespace

PartGraph BuildPartGraph(const PointCloud& cloud, const std::vector<Indices>& parts,
                         const PartGraphParams& params) {
    const float d = params.adjacency_distance;
    if (!(d > 0.0f) || !std::isfinite(d)) {
        throw InvalidArgument("adjacency_distance must be > 0 and finite");
    }
    PartGraph graph(parts.size());
    // Cell -> entries, sorted by part so each cell holds runs of one part.
    std::unordered_map<std::uint64_t, std::vector<CellEntry>> cells;
    std::unordered_map<std::uint64_t, Eigen::Vector3i> coords;
    for (std::uint32_t p = 0; p < parts.size(); ++p) {
        for (Index i : parts[p]) {
            if (i >= cloud.size()) throw InvalidArgument("part graph: point index out of range");
            const Eigen::Vector3f& x = cloud.points[i];
            if (!x.allFinite()) continue;
            const Eigen::Vector3i c = (x / d).array().floor().cast<int>();
            const std::uint64_t key = CellKey(c);
            cells[key].push_back({p, i});
            coords.emplace(key, c);
        }
    }
    const float d2 = d * d;
    // Each cell's entries come in runs of one part (parts were added in order): only runs of two
    // different parts not yet joined compare their points, and stop at the first pair within d.
    std::unordered_map<std::uint64_t, std::vector<PartRun>> runs;
    for (const auto& [key, entries] : cells) {
        auto& r = runs[key];
        for (std::size_t k = 0; k < entries.size(); ++k) {
            if (k == 0 || entries[k].part != entries[k - 1].part) {
                r.push_back({entries[k].part, static_cast<std::uint32_t>(k), 0});
            }
            r.back().end = static_cast<std::uint32_t>(k + 1);
        }
    }
    auto near = [&](const std::vector<CellEntry>& here, const PartRun& a,
                    const std::vector<CellEntry>& there, const PartRun& b) {
        for (std::uint32_t i = a.begin; i < a.end; ++i) {
            const Eigen::Vector3f& p = cloud.points[here[i].point];
            for (std::uint32_t j = b.begin; j < b.end; ++j) {
                if ((p - cloud.points[there[j].point]).squaredNorm() < d2) return true;
            }
        }
        return false;
    };
    // Deterministic order of cells.
    std::vector<std::uint64_t> keys;
    keys.reserve(cells.size());
    for (const auto& [k, v] : cells) keys.push_back(k);
    std::sort(keys.begin(), keys.end());
    for (std::uint64_t key : keys) {
        const auto& here = cells[key];
        const auto& here_runs = runs[key];
        const Eigen::Vector3i c = coords[key];
        for (int dx = -1; dx <= 1; ++dx) {
            for (int dy = -1; dy <= 1; ++dy) {
                for (int dz = -1; dz <= 1; ++dz) {
                    const std::uint64_t other = CellKey(c + Eigen::Vector3i(dx, dy, dz));
                    const auto it = cells.find(other);
                    if (it == cells.end()) continue;
                    const auto& there = it->second;
                    for (const PartRun& a : here_runs) {
                        for (const PartRun& b : runs[other]) {
                            if (b.part <= a.part || graph.Adjacent(a.part, b.part)) continue;
                            if (near(here, a, there, b)) graph.AddEdge(a.part, b.part);
                        }
                    }
                }
            }
        }
    }
    return graph;
}

namespace {

struct Esu {
    const PartGraph& g;
    std::size_t max_parts;
    const SubgraphVisitor& visit;
    std::vector<std::uint32_t> sub;
    std::vector<std::int32_t> rank;  // position of each vertex in the root order
    std::size_t count = 0;
    bool stop = false;

    bool InOrNextToSub(std::uint32_t u) const {
        for (std::uint32_t s : sub) {
            if (s == u || g.Adjacent(s, u)) return true;
        }
        return false;
    }

    void Extend(std::vector<std::uint32_t> ext, std::uint32_t root) {
        ++count;
        if (!visit(std::span<const std::uint32_t>(sub))) {
            stop = true;
            return;
        }
        if (sub.size() == max_parts) return;
        while (!ext.empty() && !stop) {
            const std::uint32_t w = ext.back();
            ext.pop_back();
            std::vector<std::uint32_t> next = ext;
            for (std::uint32_t u : g.Neighbours(w)) {
                if (rank[u] <= rank[root] || InOrNextToSub(u)) continue;
                if (std::find(next.begin(), next.end(), u) == next.end()) next.push_back(u);
            }
            sub.push_back(w);
            Extend(std::move(next), root);
            sub.pop_back();
        }
    }
};

}  // namespace

std::size_t EnumerateConnectedSubgraphs(const PartGraph& graph, std::size_t max_parts,
                                        const SubgraphVisitor& visit,
                                        std::span<const std::uint32_t> root_order) {
    if (max_parts == 0 || max_parts > kMaxSubgraphParts) {
        throw InvalidArgument("max_parts must be in [1, " + std::to_string(kMaxSubgraphParts) +
                              "]");
    }
    const std::size_t n = graph.size();
    std::vector<std::uint32_t> order(n);
    if (root_order.empty()) {
        for (std::uint32_t i = 0; i < n; ++i) order[i] = i;
    } else {
        if (root_order.size() != n) throw InvalidArgument("root_order must be a permutation");
        order.assign(root_order.begin(), root_order.end());
    }
    Esu esu{graph, max_parts, visit, {}, std::vector<std::int32_t>(n, -1)};
    for (std::size_t i = 0; i < n; ++i) {
        if (order[i] >= n || esu.rank[order[i]] >= 0) {
            throw InvalidArgument("root_order must be a permutation");
        }
        esu.rank[order[i]] = static_cast<std::int32_t>(i);
    }
    for (std::uint32_t v : order) {
        std::vector<std::uint32_t> ext;
        for (std::uint32_t u : graph.Neighbours(v)) {
            if (esu.rank[u] > esu.rank[v]) ext.push_back(u);
        }
        esu.sub.assign(1, v);
        esu.Extend(std::move(ext), v);
        if (esu.stop) break;
    }
    return esu.count;
}

std::uint64_t SubgraphKey(const PartGraph& graph, std::span<const std::uint32_t> vertices) {
    const std::size_t m = vertices.size();
    if (m == 0 || m > kMaxSubgraphParts) {
        throw InvalidArgument("subgraph key: 1 to 15 parts required");
    }
    int degrees[kMaxSubgraphParts] = {};
    for (std::size_t i = 0; i < m; ++i) {
        for (std::size_t j = i + 1; j < m; ++j) {
            if (graph.Adjacent(vertices[i], vertices[j])) {
                ++degrees[i];
                ++degrees[j];
            }
        }
    }
    std::sort(degrees, degrees + m, std::greater<int>());
    std::uint64_t key = static_cast<std::uint64_t>(m) << 60;
    for (std::size_t i = 0; i < m; ++i) {
        key |= static_cast<std::uint64_t>(std::min(degrees[i], 15)) << (56 - 4 * i);
    }
    return key;
}

std::size_t KeyParts(std::uint64_t key) { return static_cast<std::size_t>(key >> 60); }

std::vector<int> KeyDegrees(std::uint64_t key) {
    std::vector<int> d(KeyParts(key));
    for (std::size_t i = 0; i < d.size(); ++i) d[i] = static_cast<int>((key >> (56 - 4 * i)) & 15);
    return d;
}

}  // namespace multicue
