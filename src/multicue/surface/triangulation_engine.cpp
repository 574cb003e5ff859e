#include "multicue/surface/triangulation_engine.hpp"

#include <algorithm>
#include <cmath>
#include <deque>
#include <numeric>
#include <optional>

#include <Eigen/Geometry>

#include "multicue/core/point_cloud.hpp"
#include "multicue/search/kdtree.hpp"

namespace multicue::detail {

// ---------------------------------------------------------------------------------- MeshState

void MeshState::AddVertex(const Eigen::Vector3f& p, const Eigen::Vector3f& n) {
    pos.push_back(p);
    nrm.push_back(n);
    nrm_in.push_back(n);
    oriented.push_back(0);
    processed.push_back(0);
    comp.push_back(kNone);
    open_edges.push_back(0);
    head.push_back(kNone);
}

void MeshState::AddTriangle(std::uint32_t a, std::uint32_t b, std::uint32_t c) {
    const auto t = static_cast<std::uint32_t>(tris.size());
    const std::uint32_t v[3] = {a, b, c};
    // An edge whose reverse exists closes; otherwise it opens at both ends.
    for (std::uint32_t k = 0; k < 3; ++k) {
        const std::uint32_t u = v[k], w = v[(k + 1) % 3];
        const std::int32_t delta = HasDirected(w, u) ? -1 : 1;
        open_edges[u] += delta;
        open_edges[w] += delta;
    }
    tris.emplace_back(a, b, c);
    for (std::uint32_t k = 0; k < 3; ++k) {
        next_corner.push_back(head[v[k]]);
        head[v[k]] = 3 * t + k;
    }
}

bool MeshState::HasDirected(std::uint32_t a, std::uint32_t b) const {
    for (std::uint32_t c = head[a]; c != kNone; c = next_corner[c]) {
        const Triangle& t = tris[c / 3];
        if (t[(c % 3 + 1) % 3] == b) return true;
    }
    return false;
}

MeshState StateFromMesh(const TriangleMesh& mesh) {
    MeshState s;
    const std::size_t n = mesh.vertices.size();
    std::vector<Eigen::Vector3f> normals(n, Eigen::Vector3f::Zero());
    for (const Triangle& t : mesh.triangles) {
        const Eigen::Vector3f a = mesh.vertices[t[1]] - mesh.vertices[t[0]];
        const Eigen::Vector3f b = mesh.vertices[t[2]] - mesh.vertices[t[0]];
        const Eigen::Vector3f area = a.cross(b);  // area-weighted
        for (int k = 0; k < 3; ++k) normals[t[k]] += area;
    }
    s.pos.reserve(n);
    for (std::size_t i = 0; i < n; ++i) {
        Eigen::Vector3f nn = Eigen::Vector3f::UnitZ();
        if (mesh.HasVertexNormals() && mesh.vertex_normals[i].allFinite() &&
            mesh.vertex_normals[i].squaredNorm() > 0.0f) {
            nn = mesh.vertex_normals[i].normalized();
        } else if (normals[i].squaredNorm() > 0.0f) {
            nn = normals[i].normalized();
        }
        s.AddVertex(mesh.vertices[i], nn);
        s.oriented[i] = 1;
        s.processed[i] = 1;
        s.comp[i] = 0;
    }
    for (const Triangle& t : mesh.triangles) s.AddTriangle(t[0], t[1], t[2]);
    return s;
}

namespace {

// ------------------------------------------------------------------------------- 2D helpers

inline float Cross2(const Eigen::Vector2f& a, const Eigen::Vector2f& b) {
    return a.x() * b.y() - a.y() * b.x();
}

/// Proper crossing of segments ab and cd (touching at an end does not count).
bool SegmentsCross(const Eigen::Vector2f& a, const Eigen::Vector2f& b, const Eigen::Vector2f& c,
                   const Eigen::Vector2f& d) {
    const float d1 = Cross2(b - a, c - a), d2 = Cross2(b - a, d - a);
    const float d3 = Cross2(d - c, a - c), d4 = Cross2(d - c, b - c);
    return ((d1 > 0.0f && d2 < 0.0f) || (d1 < 0.0f && d2 > 0.0f)) &&
           ((d3 > 0.0f && d4 < 0.0f) || (d3 < 0.0f && d4 > 0.0f));
}

struct Frame {
    Eigen::Vector3f origin, u, v;
    explicit Frame(const Eigen::Vector3f& o, const Eigen::Vector3f& n)
        : origin(o), u(n.unitOrthogonal()), v(n.cross(n.unitOrthogonal())) {}
    Eigen::Vector2f operator()(const Eigen::Vector3f& p) const {
        const Eigen::Vector3f d = p - origin;
        return {d.dot(u), d.dot(v)};
    }
};

constexpr float kTwoPi = 6.28318530717958647692f;

inline float Wrap(float a) {
    while (a < 0.0f) a += kTwoPi;
    while (a >= kTwoPi) a -= kTwoPi;
    return a;
}

// --------------------------------------------------------------------------------- the growth

struct Edge {
    std::uint32_t a, b;
};

class Grower {
  public:
    Grower(MeshState& m, const Indices& working, const GrowSettings& s)
        : m_(m), working_(working), s_(s) {
        PointCloud local;
        local.points.reserve(working.size());
        for (std::uint32_t g : working) local.points.push_back(m.pos[g]);
        local.SetUnorganized();
        tree_.emplace(local);
    }

    void Process(std::uint32_t p, bool fan) {
        if (!Neighbourhood(p)) return;
        OrientSource(p);
        Candidates(p);
        if (fan) Fan(p);
        CloseGaps(p);
    }

    void Push(std::uint32_t v) {
        if (!m_.processed[v]) queue_.push_back(v);
    }
    bool Pop(std::uint32_t& v) {
        while (!queue_.empty()) {
            v = queue_.front();
            queue_.pop_front();
            if (!m_.processed[v]) return true;
        }
        return false;
    }

    GrowStats stats;

  private:
    /// Neighbours within mu * d0 (at most search_radius), self and duplicates excluded.
    bool Neighbourhood(std::uint32_t p) {
        // d0 first, then only the ball of radius mu * d0, which usually holds far fewer points
        // than one of search_radius (k-nearest queries for large k cost more than the two).
        const float eps2 = 1e-12f * s_.search_radius * s_.search_radius;
        float radius = s_.search_radius;
        const std::size_t found = tree_->SearchKnn(m_.pos[p], 3, idx_, d2_);
        std::size_t first = 0;
        while (first < found && d2_[first] <= eps2) ++first;
        if (first < found) radius = std::min(radius, 1.0001f * s_.mu * std::sqrt(d2_[first]));
        // Unbounded radius search, then the nearest max_neighbors (+ p itself): for the few
        // dozen points of the ball this beats a bounded k-nearest search.
        tree_->SearchRadius(m_.pos[p], radius, idx_, d2_);
        const auto keep = static_cast<std::size_t>(s_.max_neighbors) + 1;
        if (idx_.size() > keep) {
            idx_.resize(keep);
            d2_.resize(keep);
        }
        nb_.clear();
        float d0_2 = -1.0f;
        for (std::size_t j = 0; j < idx_.size(); ++j) {
            if (d2_[j] <= eps2) continue;
            if (d0_2 < 0.0f) d0_2 = d2_[j];
            const float r = std::min(s_.mu * s_.mu * d0_2, s_.search_radius * s_.search_radius);
            if (d2_[j] > r) break;
            const std::uint32_t g = working_[idx_[j]];
            if (g != p) nb_.push_back(g);
        }
        return !nb_.empty();
    }

    /// A source without an orientation takes it from its nearest oriented compatible neighbour,
    /// or starts a new component (a seed).
    void OrientSource(std::uint32_t p) {
        if (m_.oriented[p]) return;
        for (std::uint32_t c : nb_) {
            if (!m_.oriented[c]) continue;
            const float d = m_.nrm[p].dot(m_.nrm[c]);
            if (std::abs(d) < s_.cos_surface) continue;
            if (d < 0.0f) m_.nrm[p] = -m_.nrm[p];
            m_.oriented[p] = 1;
            m_.comp[p] = m_.comp[c];
            return;
        }
        m_.oriented[p] = 1;
        m_.comp[p] = NewComponent();
        ++stats.seeds;
    }

    std::uint32_t NewComponent() {
        const auto id = static_cast<std::uint32_t>(parent_.size());
        parent_.push_back(id);
        return id;
    }

  public:
    std::uint32_t Find(std::uint32_t c) {
        while (parent_[c] != c) c = parent_[c] = parent_[parent_[c]];
        return c;
    }
    std::size_t ComponentCount() const { return parent_.size(); }
    void InitComponents(std::uint32_t count) {
        parent_.resize(count);
        std::iota(parent_.begin(), parent_.end(), 0u);
    }

  private:
    /// Neighbours that may still get triangles and whose normals are compatible with p's; the
    /// front edges around them; p's tangent frame.
    void Candidates(std::uint32_t p) {
        cand_.clear();
        const Eigen::Vector3f& n = m_.nrm[p];
        for (std::uint32_t c : nb_) {
            const float d = n.dot(m_.nrm[c]);
            if ((m_.oriented[c] ? d : std::abs(d)) < s_.cos_surface) continue;
            if (m_.IsInterior(c)) continue;
            cand_.push_back(c);
        }
        front_.clear();
        auto collect = [&](std::uint32_t v) {
            if (m_.IsInterior(v)) return;
            m_.ForEachFrontEdge(
                v,
                [&](std::uint32_t x) {
                    front_.push_back({v, x});
                },
                [&](std::uint32_t y) {
                    front_.push_back({y, v});
                });
        };
        collect(p);
        for (std::uint32_t c : nb_) collect(c);
        frame_.emplace(m_.pos[p], n);
    }

    /// Local Delaunay fan of p in its tangent plane: clips a square by the bisectors of the
    /// candidates, nearest first, and connects consecutive neighbours of the cell's edges.
    void Fan(std::uint32_t p) {
        const float r = s_.search_radius;
        poly_.assign({{{-r, -r}, kNone}, {{r, -r}, kNone}, {{r, r}, kNone}, {{-r, r}, kNone}});
        float cell2 = 2.0f * r * r;
        for (std::uint32_t c : cand_) {
            const Eigen::Vector2f q = (*frame_)(m_.pos[c]);
            const float q2 = q.squaredNorm();
            if (q2 < 1e-20f) continue;
            if (q2 * 0.25f > cell2) break;  // candidates come nearest first
            Clip(q, 0.5f * q2, c);
            cell2 = 0.0f;
            for (const auto& v : poly_) cell2 = std::max(cell2, v.first.squaredNorm());
        }
        const std::size_t k = poly_.size();
        fan_.clear();
        for (std::size_t i = 0; i < k; ++i) {
            const std::uint32_t a = poly_[i].second, b = poly_[(i + 1) % k].second;
            if (a != kNone && b != kNone && a != b) fan_.push_back({a, b});
        }
        for (const Edge& e : fan_) TryTriangle(p, e.a, e.b, false);
    }

    /// Keeps the part of the cell with x . q <= h; the new edge is labelled with c.
    void Clip(const Eigen::Vector2f& q, float h, std::uint32_t c) {
        clipped_.clear();
        const std::size_t k = poly_.size();
        for (std::size_t i = 0; i < k; ++i) {
            const auto& [pi, li] = poly_[i];
            const auto& pj = poly_[(i + 1) % k].first;
            const float fi = pi.dot(q) - h, fj = pj.dot(q) - h;
            const bool in_i = fi <= 0.0f, in_j = fj <= 0.0f;
            if (in_i) clipped_.push_back({pi, li});
            if (in_i != in_j) {
                const Eigen::Vector2f x = pi + (fi / (fi - fj)) * (pj - pi);
                clipped_.push_back({x, in_i ? c : li});
            }
        }
        poly_.swap(clipped_);
    }

    /// Does the triangle (v, s, e) overlap, around v, the triangles already at v?
    bool SectorOverlaps(std::uint32_t v, std::uint32_t s, std::uint32_t e) const {
        if (!m_.HasTriangles(v)) return false;
        const Frame f(m_.pos[v], m_.nrm[v]);
        // Pseudo-angles in [0, 4): monotonic in the angle and much cheaper than atan2; sums of
        // differences modulo 4 go round the circle as angles do.
        auto angle = [&](std::uint32_t w) {
            const Eigen::Vector2f q = f(m_.pos[w]);
            const float r = q.x() / (std::abs(q.x()) + std::abs(q.y()) + 1e-30f);
            return q.y() >= 0.0f ? 1.0f - r : 3.0f + r;
        };
        auto wrap4 = [](float a) { return a < 0.0f ? a + 4.0f : (a >= 4.0f ? a - 4.0f : a); };
        const float as = angle(s);
        const float w1 = wrap4(angle(e) - as);
        constexpr float kEps = 1e-5f;
        bool overlap = false;
        m_.ForEachFan(v, [&](std::uint32_t x, std::uint32_t y) {
            if (overlap) return;
            const float px = angle(x);
            const float ax = wrap4(px - as);
            const float w2 = wrap4(angle(y) - px);
            if (ax < w1 - kEps || ax + w2 > 4.0f + kEps) overlap = true;
        });
        return overlap;
    }

    /// v's normal, flipped to agree with `ref` if v has no orientation yet.
    Eigen::Vector3f Oriented(std::uint32_t v, const Eigen::Vector3f& ref) const {
        const Eigen::Vector3f& n = m_.nrm[v];
        return (!m_.oriented[v] && n.dot(ref) < 0.0f) ? Eigen::Vector3f(-n) : n;
    }

    /// Writes triangle (a, b, c), a being the source, if it passes every test.
    bool TryTriangle(std::uint32_t a, std::uint32_t b, std::uint32_t c, bool gap) {
        // Cheapest first: most fan triangles of a point inside the mesh exist already.
        if (m_.HasDirected(a, b) || m_.HasDirected(b, c) || m_.HasDirected(c, a)) return false;
        const Eigen::Vector3f &pa = m_.pos[a], &pb = m_.pos[b], &pc = m_.pos[c];
        const Eigen::Vector3f ab = pb - pa, ac = pc - pa, bc = pc - pb;
        const float lab = ab.norm(), lac = ac.norm(), lbc = bc.norm();
        if (!(lab > 0.0f && lac > 0.0f && lbc > 0.0f)) return false;
        if (lbc > s_.search_radius || lab > s_.search_radius || lac > s_.search_radius)
            return false;
        const float ca = ab.dot(ac) / (lab * lac);
        const float cb = -ab.dot(bc) / (lab * lbc);
        const float cc = ac.dot(bc) / (lac * lbc);
        for (float cs : {ca, cb, cc})
            if (cs > s_.cos_min_angle || cs < s_.cos_max_angle) return false;
        const Eigen::Vector3f nt = ab.cross(ac).normalized();
        const Eigen::Vector3f& na = m_.nrm[a];
        const Eigen::Vector3f nb = Oriented(b, na), nc = Oriented(c, na);
        if (!(nt.dot(na) > 0.0f && nt.dot(nb) > 0.0f && nt.dot(nc) > 0.0f)) return false;
        if (SectorOverlaps(a, b, c) || SectorOverlaps(b, c, a) || SectorOverlaps(c, a, b))
            return false;
        const Frame& f = *frame_;
        const Eigen::Vector2f qa = f(pa), qb = f(pb), qc = f(pc);
        const std::pair<std::uint32_t, std::uint32_t> sides[3] = {{a, b}, {b, c}, {c, a}};
        const Eigen::Vector2f qs[3][2] = {{qa, qb}, {qb, qc}, {qc, qa}};
        for (const Edge& e : front_) {
            const Eigen::Vector2f fa = f(m_.pos[e.a]), fb = f(m_.pos[e.b]);
            for (int k = 0; k < 3; ++k) {
                const auto [s0, s1] = sides[k];
                if (e.a == s0 || e.a == s1 || e.b == s0 || e.b == s1) continue;
                if (SegmentsCross(qs[k][0], qs[k][1], fa, fb)) return false;
            }
        }
        // Accepted: b and c join a's orientation component.
        for (std::uint32_t v : {b, c}) {
            if (!m_.oriented[v]) {
                if (m_.nrm[v].dot(na) < 0.0f) m_.nrm[v] = -m_.nrm[v];
                m_.oriented[v] = 1;
                m_.comp[v] = m_.comp[a];
            } else if (Find(m_.comp[v]) != Find(m_.comp[a])) {
                parent_[Find(m_.comp[v])] = Find(m_.comp[a]);
            }
        }
        m_.AddTriangle(a, b, c);
        front_.push_back({a, b});
        front_.push_back({b, c});
        front_.push_back({c, a});
        ++stats.triangles;
        if (gap) ++stats.gap_triangles;
        Push(b);
        Push(c);
        return true;
    }

    /// Closes the gaps around p between an incoming front edge y -> p and the next outgoing one
    /// p -> x counter-clockwise (fronts touching in p, Figure 2.10), when the gap is narrower than
    /// max_angle and holds no unconnected candidate.
    void CloseGaps(std::uint32_t p) {
        if (!m_.HasTriangles(p)) return;
        const Frame f(m_.pos[p], m_.nrm[p]);
        for (int round = 0; round < 8; ++round) {
            ins_.clear();
            outs_.clear();
            m_.ForEachFrontEdge(
                p, [&](std::uint32_t x) { outs_.push_back(x); },
                [&](std::uint32_t y) { ins_.push_back(y); });
            if (ins_.empty() || outs_.empty()) return;
            bool changed = false;
            for (std::uint32_t y : ins_) {
                const Eigen::Vector2f qy = f(m_.pos[y]);
                const float ay = std::atan2(qy.y(), qy.x());
                std::uint32_t best = kNone;
                float best_gap = s_.max_angle;
                for (std::uint32_t x : outs_) {
                    if (x == y) continue;
                    const Eigen::Vector2f qx = f(m_.pos[x]);
                    const float gap = Wrap(std::atan2(qx.y(), qx.x()) - ay);
                    if (gap > 0.0f && gap < best_gap) {
                        best_gap = gap;
                        best = x;
                    }
                }
                if (best == kNone || HoldsCandidate(f, p, y, best)) continue;
                if (TryTriangle(p, y, best, true)) {
                    changed = true;
                    break;
                }
            }
            if (!changed) return;
        }
    }

    /// Is an unconnected candidate strictly inside the projected triangle (p, a, b)?
    bool HoldsCandidate(const Frame& f, std::uint32_t p, std::uint32_t a, std::uint32_t b) const {
        const Eigen::Vector2f qp = f(m_.pos[p]), qa = f(m_.pos[a]), qb = f(m_.pos[b]);
        for (std::uint32_t c : cand_) {
            if (c == a || c == b || m_.HasTriangles(c)) continue;
            const Eigen::Vector2f q = f(m_.pos[c]);
            if (Cross2(qa - qp, q - qp) > 0.0f && Cross2(qb - qa, q - qa) > 0.0f &&
                Cross2(qp - qb, q - qb) > 0.0f)
                return true;
        }
        return false;
    }

    MeshState& m_;
    const Indices& working_;
    const GrowSettings& s_;
    std::optional<KdTree> tree_;
    std::deque<std::uint32_t> queue_;
    std::vector<std::uint32_t> parent_;
    Indices idx_;
    std::vector<float> d2_;
    std::vector<std::uint32_t> nb_, cand_, ins_, outs_;
    std::vector<Edge> front_, fan_;
    std::vector<std::pair<Eigen::Vector2f, std::uint32_t>> poly_, clipped_;
    std::optional<Frame> frame_;
};

}  // namespace

GrowStats Grow(MeshState& m, const Indices& working, const Indices& first,
               const GrowSettings& settings, std::uint32_t first_new_comp) {
    if (working.empty()) return {};
    Grower g(m, working, settings);
    g.InitComponents(first_new_comp);
    auto drain = [&] {
        std::uint32_t v;
        while (g.Pop(v)) {
            m.processed[v] = 1;
            g.Process(v, true);
        }
    };
    for (std::uint32_t v : first) {
        // Existing boundary vertices: close gaps and extend their fans into the new points.
        g.Process(v, true);
        drain();
    }
    for (std::uint32_t v : working) {
        if (m.processed[v]) continue;
        m.processed[v] = 1;
        g.Process(v, true);
        drain();
    }
    // Gaps opened at vertices after they were processed.
    for (std::uint32_t v : working)
        if (m.HasTriangles(v) && !m.IsInterior(v)) g.Process(v, false);

    // Orientation vote per component (new components only): the mesh faces the way most of the
    // given normals do.
    const std::size_t components = g.ComponentCount();
    std::vector<std::uint32_t> root_of(working.size(), kNone);
    for (std::size_t i = 0; i < working.size(); ++i) {
        const std::uint32_t c = m.comp[working[i]];
        if (c != kNone && c < components) root_of[i] = g.Find(c);
    }
    std::vector<long> votes(components, 0);
    std::vector<std::uint8_t> anchored(components, 0);
    for (std::uint32_t c = 0; c < first_new_comp && c < components; ++c) anchored[g.Find(c)] = 1;
    for (std::size_t i = 0; i < working.size(); ++i) {
        if (root_of[i] == kNone || !m.HasTriangles(working[i])) continue;
        const std::uint32_t v = working[i];
        votes[root_of[i]] += m.nrm[v].dot(m.nrm_in[v]) >= 0.0f ? 1 : -1;
    }
    std::vector<std::uint8_t> flip(votes.size(), 0);
    for (std::size_t c = 0; c < votes.size(); ++c) flip[c] = !anchored[c] && votes[c] < 0;
    if (std::find(flip.begin(), flip.end(), 1) != flip.end()) {
        std::vector<std::uint8_t> flip_vertex(m.size(), 0);
        for (std::size_t i = 0; i < working.size(); ++i) {
            if (root_of[i] != kNone && flip[root_of[i]]) {
                flip_vertex[working[i]] = 1;
                m.nrm[working[i]] = -m.nrm[working[i]];
            }
        }
        for (auto& t : m.tris)
            if (flip_vertex[t[0]]) std::swap(t[1], t[2]);
        // The swaps moved vertices between corner slots: rebuild the corner lists.
        std::fill(m.head.begin(), m.head.end(), kNone);
        m.next_corner.assign(3 * m.tris.size(), kNone);
        for (std::uint32_t t = 0; t < m.tris.size(); ++t) {
            for (std::uint32_t k = 0; k < 3; ++k) {
                m.next_corner[3 * t + k] = m.head[m.tris[t][k]];
                m.head[m.tris[t][k]] = 3 * t + k;
            }
        }
    }
    return g.stats;
}

}  // namespace multicue::detail
