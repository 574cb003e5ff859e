// Handle variety for training kitchens (VaryHandles).

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include <fmt/format.h>

#include "multicue/core/disjoint_sets.hpp"
#include "multicue/core/exceptions.hpp"
#include "multicue/sim/kitchen_scene.hpp"
#include "multicue/sim/rng.hpp"

namespace multicue::sim {
namespace {

constexpr float kJoinGap = 0.01f;  // pieces of one handle (bar, mounts) lie this close [m]

struct Piece {
    std::vector<std::uint32_t> vertices;
    Eigen::AlignedBox3f box;
};

/// The handles of a mesh: the vertices of its "handle" triangles split into connected pieces,
/// pieces whose boxes come within kJoinGap joined. Vertices shared with other triangles are left
/// out (they belong to the front as well).
std::vector<Piece> HandlePieces(const PartMesh& m, std::vector<bool>& other_vertex) {
    const std::size_t nv = m.mesh.vertices.size();
    std::vector<bool> handle_part(m.part_names.size(), false);
    for (std::size_t p = 0; p < m.part_names.size(); ++p) {
        handle_part[p] = m.part_names[p].find("handle") != std::string::npos;
    }
    std::vector<bool> handle_vertex(nv, false);
    other_vertex.assign(nv, false);
    detail::DisjointSets sets(nv);
    for (std::size_t t = 0; t < m.mesh.triangles.size(); ++t) {
        const auto& tri = m.mesh.triangles[t];
        const bool h = t < m.triangle_parts.size() && handle_part[m.triangle_parts[t]];
        for (int c = 0; c < 3; ++c) (h ? handle_vertex : other_vertex)[tri[c]] = true;
        if (h) {
            sets.Unite(tri[0], tri[1]);
            sets.Unite(tri[0], tri[2]);
        }
    }
    std::vector<Piece> pieces;
    std::vector<int> piece_of(nv, -1);
    for (std::uint32_t v = 0; v < nv; ++v) {
        if (!handle_vertex[v] || other_vertex[v]) continue;
        const Index r = sets.Find(v);
        if (piece_of[r] < 0) {
            piece_of[r] = static_cast<int>(pieces.size());
            pieces.emplace_back();
        }
        Piece& p = pieces[static_cast<std::size_t>(piece_of[r])];
        p.vertices.push_back(v);
        p.box.extend(m.mesh.vertices[v]);
    }
    // Join pieces that touch (a bar and its mounts are often separate meshes).
    for (bool changed = true; changed;) {
        changed = false;
        for (std::size_t a = 0; a < pieces.size() && !changed; ++a) {
            for (std::size_t b = a + 1; b < pieces.size(); ++b) {
                Eigen::AlignedBox3f grown = pieces[a].box;
                grown.min().array() -= kJoinGap;
                grown.max().array() += kJoinGap;
                if (!grown.intersects(pieces[b].box)) continue;
                pieces[a].vertices.insert(pieces[a].vertices.end(), pieces[b].vertices.begin(),
                                          pieces[b].vertices.end());
                pieces[a].box.extend(pieces[b].box);
                pieces.erase(pieces.begin() + static_cast<long>(b));
                changed = true;
                break;
            }
        }
    }
    return pieces;
}

}  // namespace

void HandleVariation::Validate() const {
    auto fail = [](const char* what, float v) {
        throw InvalidArgument(fmt::format("handle variation: {} out of range, got {}", what, v));
    };
    if (!(chance >= 0.0f && chance <= 1.0f)) fail("chance (need [0, 1])", chance);
    if (!(min_length > 0.0f) || !(max_length >= min_length) || !(max_length <= 5.0f)) {
        fail("min_length/max_length (need 0 < min <= max <= 5 m)", min_length);
    }
    if (!(min_shrink > 0.0f && min_shrink <= 1.0f)) fail("min_shrink (need (0, 1])", min_shrink);
    if (!(front_margin >= 0.0f && front_margin < 1.0f)) fail("front_margin", front_margin);
    if (!(min_elongation >= 1.0f) || !std::isfinite(min_elongation)) {
        fail("min_elongation (need >= 1)", min_elongation);
    }
    if (!(min_reach_scale > 0.0f) || !(max_reach_scale >= min_reach_scale) ||
        !(max_reach_scale <= 10.0f)) {
        fail("min_reach_scale/max_reach_scale (need 0 < min <= max <= 10)", min_reach_scale);
    }
    if (!(min_thickness_scale > 0.0f) || !(max_thickness_scale >= min_thickness_scale) ||
        !(max_thickness_scale <= 10.0f)) {
        fail("min_thickness_scale/max_thickness_scale (need 0 < min <= max <= 10)",
             min_thickness_scale);
    }
}

int VaryHandles(KitchenScene& kitchen, const HandleVariation& v, std::uint64_t seed) {
    v.Validate();
    StreamRng rng(seed, 41);
    // Cross-sections draw from their own stream, so that the lengths stay those of a variation
    // without them.
    StreamRng cross_rng(seed, 42);
    const bool vary_reach = v.max_reach_scale > v.min_reach_scale || v.min_reach_scale != 1.0f;
    const bool vary_thickness =
        v.max_thickness_scale > v.min_thickness_scale || v.min_thickness_scale != 1.0f;
    auto log_uniform = [](float lo, float hi, double u) {
        return static_cast<float>(std::exp(std::log(lo) + (std::log(hi) - std::log(lo)) * u));
    };
    int varied = 0;
    for (std::size_t o = 0; o < kitchen.scene.objects.size(); ++o) {
        if (kitchen.truth[o].instance < 0) continue;
        SceneObject& object = kitchen.scene.objects[o];
        if (!object.mesh) continue;
        std::vector<bool> front_vertex;
        const std::vector<Piece> pieces = HandlePieces(*object.mesh, front_vertex);
        if (pieces.empty()) continue;
        Eigen::AlignedBox3f front;
        for (std::size_t i = 0; i < front_vertex.size(); ++i) {
            if (front_vertex[i]) front.extend(object.mesh->mesh.vertices[i]);
        }
        if (front.isEmpty()) continue;  // a handle link of its own: nothing to measure it by
        std::shared_ptr<PartMesh> copy;
        for (const Piece& piece : pieces) {
            // Draw for every piece, varied or not, so one handle's draw does not shift the next.
            const double keep = rng.Uniform();
            const double u = rng.Uniform();
            const double u_reach = vary_reach ? cross_rng.Uniform() : 0.0;
            const double u_thick = vary_thickness ? cross_rng.Uniform() : 0.0;
            const Eigen::Vector3f size = piece.box.sizes();
            int axis = 0;
            size.maxCoeff(&axis);
            const float length = size[axis];
            float second = 0.0f;
            for (int a = 0; a < 3; ++a) {
                if (a != axis) second = std::max(second, size[a]);
            }
            if (keep >= v.chance || length < v.min_elongation * second) continue;
            const float c = piece.box.center()[axis];
            const float room = 2.0f * std::min(c - front.min()[axis], front.max()[axis] - c) -
                               2.0f * v.front_margin;
            const float lo = std::max(v.min_length, v.min_shrink * length);
            const float hi = std::min(v.max_length, room);
            // The outer fifth at each end (mounts) moves rigidly, the middle is scaled.
            const float end = 0.2f * length;
            const float half = 0.5f * length - end;
            const float new_half = hi > lo ? 0.5f * log_uniform(lo, hi, u) - end : -1.0f;
            const bool stretch = half > 0.0f && new_half > 0.0f;
            if (!stretch && !vary_reach && !vary_thickness) continue;
            if (!copy) copy = std::make_shared<PartMesh>(*object.mesh);
            if (stretch) {
                for (const std::uint32_t i : piece.vertices) {
                    float& x = copy->mesh.vertices[i][axis];
                    const float d = x - c;
                    x = std::abs(d) <= half
                            ? c + d * (new_half / half)
                            : c + d + (d < 0.0f ? half - new_half : new_half - half);
                }
            }
            // Cross-section: the axis along which the handle stands out of its front is the
            // front's normal; the front's surface there is the base its reach is scaled from.
            int normal = -1;
            float out = -1e9f;
            for (int a = 0; a < 3; ++a) {
                if (a == axis) continue;
                const float beyond = std::max(piece.box.max()[a] - front.max()[a],
                                              front.min()[a] - piece.box.min()[a]);
                if (beyond > out) {
                    out = beyond;
                    normal = a;
                }
            }
            const int across = 3 - axis - normal;
            const bool outwards = piece.box.center()[normal] > front.center()[normal];
            const float base = outwards ? front.max()[normal] : front.min()[normal];
            const float reach =
                vary_reach ? log_uniform(v.min_reach_scale, v.max_reach_scale, u_reach) : 1.0f;
            const float thick =
                vary_thickness ? log_uniform(v.min_thickness_scale, v.max_thickness_scale, u_thick)
                               : 1.0f;
            const float mid = piece.box.center()[across];
            for (const std::uint32_t i : piece.vertices) {
                Eigen::Vector3f& x = copy->mesh.vertices[i];
                if (vary_reach) x[normal] = base + (x[normal] - base) * reach;
                if (vary_thickness) x[across] = mid + (x[across] - mid) * thick;
            }
            ++varied;
        }
        if (copy) object.mesh = std::move(copy);
    }
    return varied;
}

}  // namespace multicue::sim
