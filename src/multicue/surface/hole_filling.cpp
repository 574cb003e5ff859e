/// \file Hole filling from boundary loops (section 2.3.2): ear clipping of small loops, each new
/// triangle oriented like the mesh around the hole.

#include <algorithm>
#include <cmath>
#include <unordered_set>

#include <Eigen/Geometry>

#include "multicue/surface/triangulation_engine.hpp"

namespace multicue::detail {
namespace {

inline float Cross2d(const Eigen::Vector2f& a, const Eigen::Vector2f& b) {
    return a.x() * b.y() - a.y() * b.x();
}

inline std::uint64_t EdgeKey(std::uint32_t a, std::uint32_t b) {
    return (std::uint64_t{a} << 32) | b;
}

/// Ear clipping of one loop given in fill order (consecutive vertices are the new directed
/// edges). Returns the number of triangles added.
std::size_t FillLoop(MeshState& m, std::vector<std::uint32_t> poly, const Eigen::Vector3f& n) {
    std::size_t added = 0;
    const Eigen::Vector3f u = n.unitOrthogonal(), w = n.cross(u);
    auto q = [&](std::uint32_t v) { return Eigen::Vector2f(m.pos[v].dot(u), m.pos[v].dot(w)); };
    while (poly.size() >= 3) {
        const std::size_t k = poly.size();
        std::size_t best = k;
        float best_score = -1.0f;
        for (std::size_t i = 0; i < k; ++i) {
            const std::uint32_t a = poly[(i + k - 1) % k], b = poly[i], c = poly[(i + 1) % k];
            if (a == c) continue;
            const Eigen::Vector2f qa = q(a), qb = q(b), qc = q(c);
            if (!(Cross2d(qb - qa, qc - qb) > 0.0f)) continue;  // reflex or flat
            if (k > 3 && (m.HasDirected(c, a) || m.HasDirected(a, c))) continue;
            if (k == 3 && (m.HasDirected(a, b) || m.HasDirected(b, c) || m.HasDirected(c, a)))
                continue;
            bool inside = false;
            for (std::uint32_t o : poly) {
                if (o == a || o == b || o == c) continue;
                const Eigen::Vector2f qo = q(o);
                if (Cross2d(qb - qa, qo - qa) > 0.0f && Cross2d(qc - qb, qo - qb) > 0.0f &&
                    Cross2d(qa - qc, qo - qc) > 0.0f) {
                    inside = true;
                    break;
                }
            }
            if (inside) continue;
            // Quality: the smallest angle of the ear.
            const Eigen::Vector3f pa = m.pos[a], pb = m.pos[b], pc = m.pos[c];
            auto ang = [](const Eigen::Vector3f& x, const Eigen::Vector3f& y) {
                return std::acos(std::clamp(x.normalized().dot(y.normalized()), -1.0f, 1.0f));
            };
            const float score =
                std::min({ang(pb - pa, pc - pa), ang(pa - pb, pc - pb), ang(pa - pc, pb - pc)});
            if (score > best_score) {
                best_score = score;
                best = i;
            }
        }
        if (best == k) break;
        const std::uint32_t a = poly[(best + k - 1) % k], b = poly[best], c = poly[(best + 1) % k];
        m.AddTriangle(a, b, c);
        ++added;
        poly.erase(poly.begin() + static_cast<std::ptrdiff_t>(best));
        if (k == 3) break;
    }
    return added;
}

}  // namespace

std::size_t FillHoles(MeshState& m, const Indices& around, int max_edges) {
    if (max_edges < 3) return 0;
    std::unordered_set<std::uint64_t> visited;
    std::size_t added = 0;
    std::vector<std::uint32_t> loop;
    for (std::uint32_t start : around) {
        if (!m.HasTriangles(start)) continue;
        // Boundary edges leaving `start`: start -> x with no x -> start.
        std::vector<std::uint32_t> outs;
        m.ForEachFan(start, [&](std::uint32_t x, std::uint32_t) {
            if (!m.HasDirected(x, start)) outs.push_back(x);
        });
        for (std::uint32_t first : outs) {
            if (!visited.insert(EdgeKey(start, first)).second) continue;
            loop.assign({start, first});
            bool closed = false;
            while (static_cast<int>(loop.size()) <= max_edges + 1) {
                const std::uint32_t b = loop.back();
                std::uint32_t next = kNone;
                m.ForEachFan(b, [&](std::uint32_t x, std::uint32_t) {
                    if (next == kNone && !m.HasDirected(x, b) && !visited.count(EdgeKey(b, x)))
                        next = x;
                });
                if (next == kNone) break;
                visited.insert(EdgeKey(b, next));
                if (next == start) {
                    closed = true;
                    break;
                }
                loop.push_back(next);
            }
            if (!closed || static_cast<int>(loop.size()) > max_edges) continue;
            // Normal of the surrounding surface and of the loop in fill (reversed) order.
            Eigen::Vector3f around_n = Eigen::Vector3f::Zero();
            for (std::uint32_t v : loop) around_n += m.nrm[v];
            std::vector<std::uint32_t> fill(loop.rbegin(), loop.rend());
            Eigen::Vector3f newell = Eigen::Vector3f::Zero();
            for (std::size_t i = 0; i < fill.size(); ++i)
                newell += m.pos[fill[i]].cross(m.pos[fill[(i + 1) % fill.size()]]);
            if (!(newell.dot(around_n) > 0.0f)) continue;  // the outer rim, not a hole
            added += FillLoop(m, std::move(fill), around_n.normalized());
        }
    }
    return added;
}

}  // namespace multicue::detail
