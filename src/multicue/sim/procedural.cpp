#include "multicue/sim/procedural.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

#include <fmt/format.h>

#include "multicue/core/exceptions.hpp"
#include "multicue/sim/sim_math_internal.hpp"

namespace multicue::sim {
namespace {

using math_internal::kPi;

using math_internal::U;

PartMesh Single(TriangleMesh mesh, const std::string& part) {
    PartMesh pm;
    pm.part_names = {part};
    pm.triangle_parts.assign(mesh.triangles.size(), 0);
    pm.mesh = std::move(mesh);
    return pm;
}

/// A tube of radius `tube` swept along a circular arc in the x-z plane (centre (cx, 0, cz),
/// radius `arc`, angles a0..a1 from +x towards +z); a mug or pitcher handle.
PartMesh MakeHandle(float cx, float cz, float arc, float tube, float a0, float a1,
                    const std::string& part) {
    const int n_arc = 16, n_tube = 10;
    TriangleMesh m;
    for (int i = 0; i <= n_arc; ++i) {
        const float a = a0 + (a1 - a0) * static_cast<float>(i) / n_arc;
        const Eigen::Vector3f c(cx + arc * std::cos(a), 0.0f, cz + arc * std::sin(a));
        const Eigen::Vector3f radial(std::cos(a), 0.0f, std::sin(a));
        for (int j = 0; j < n_tube; ++j) {
            const float b = 2 * kPi * static_cast<float>(j) / n_tube;
            m.vertices.push_back(
                c + tube * (std::cos(b) * radial + std::sin(b) * Eigen::Vector3f::UnitY()));
        }
    }
    for (int i = 0; i < n_arc; ++i) {
        for (int j = 0; j < n_tube; ++j) {
            const auto a = static_cast<std::uint32_t>(i * n_tube + j);
            const auto b = static_cast<std::uint32_t>(i * n_tube + (j + 1) % n_tube);
            const auto c = a + static_cast<std::uint32_t>(n_tube);
            const auto d = b + static_cast<std::uint32_t>(n_tube);
            m.triangles.emplace_back(a, b, d);
            m.triangles.emplace_back(a, d, c);
        }
    }
    return Single(std::move(m), part);
}

PartMesh Ball(StreamRng& rng) {
    const float r = U(rng, 0.03f, 0.12f);
    const int rings = 16;
    std::vector<ProfilePoint> profile;
    for (int i = 0; i <= rings; ++i) {
        const float a = -kPi / 2 + kPi * static_cast<float>(i) / rings;
        profile.push_back({i == 0 || i == rings ? 0.0f : r * std::cos(a), r + r * std::sin(a), 0});
    }
    return MakeRevolutionMesh(profile, {"body"});
}

// Segments of the revolution meshes: between two profile vertices the facets of a ring of radius
// r come as close to the axis as r * cos(pi / segments).
constexpr int kSegments = 48;

/// The inner wall of a container from its profile points `inner` (floor edge first, upwards):
/// pulled in to the facets of the mesh (see kSegments).
std::vector<Eigen::Vector2f> Cavity(const std::vector<ProfilePoint>& inner) {
    const float inset = std::cos(kPi / kSegments);
    std::vector<Eigen::Vector2f> out;
    for (const auto& q : inner) out.emplace_back(q.r * inset, q.z);
    return out;
}

PartMesh Bowl(StreamRng& rng, std::vector<Eigen::Vector2f>& cavity) {
    const float R = U(rng, 0.06f, 0.12f), h = R * U(rng, 0.45f, 0.6f), t = 0.004f;
    const float Rb = R * U(rng, 0.35f, 0.5f);
    std::vector<ProfilePoint> p{{0.0f, 0.0f, 0}};
    const int n = 10;
    for (int i = 0; i <= n; ++i) {
        const float s = static_cast<float>(i) / n * kPi / 2;
        p.push_back({Rb + (R - Rb) * std::sin(s), h * (1 - std::cos(s)), 0});
    }
    for (int i = n; i >= 0; --i) {
        const float s = static_cast<float>(i) / n * kPi / 2;
        p.push_back({Rb - t + (R - Rb) * std::sin(s), t + (h - t) * (1 - std::cos(s)), 0});
    }
    p.push_back({0.0f, t, 0});
    // Inner wall: the second run of profile points, reversed (floor edge first).
    cavity = Cavity(std::vector<ProfilePoint>(p.rbegin() + 1, p.rbegin() + 2 + n));
    return MakeRevolutionMesh(p, {"bowl"}, kSegments);
}

PartMesh Plate(StreamRng& rng, std::vector<Eigen::Vector2f>& cavity) {
    const float R = U(rng, 0.08f, 0.15f), H = U(rng, 0.015f, 0.025f), t = 0.004f;
    const std::vector<ProfilePoint> p{{0.0f, 0.0f, 0},    {0.6f * R, 0.0f, 0},       {R, H, 0},
                                      {R - 0.006f, H, 0}, {0.6f * R - 0.004f, t, 0}, {0.0f, t, 0}};
    cavity = Cavity({p[4], p[3]});
    return MakeRevolutionMesh(p, {"plate"}, kSegments);
}

PartMesh Can(StreamRng& rng) {
    const float r = U(rng, 0.03f, 0.05f), h = U(rng, 0.08f, 0.17f);
    return MakeRevolutionMesh({{0, 0, 0}, {r, 0, 1}, {r, h, 2}, {0, h, 2}},
                              {"bottom", "body", "top"});
}

PartMesh Cup(float rb, float rt, float h, float t) {
    return MakeRevolutionMesh(
        {{0, 0, 0}, {rb, 0, 0}, {rt, h, 0}, {rt - t, h, 0}, {rb - t, t, 0}, {0, t, 0}}, {"body"});
}

PartMesh Mug(StreamRng& rng) {
    const float r = U(rng, 0.035f, 0.05f), h = U(rng, 0.08f, 0.12f);
    PartMesh m = Cup(r, r, h, 0.004f);
    const float arc = h * U(rng, 0.25f, 0.32f);
    m.AppendParts(MakeHandle(r, h / 2, arc, 0.006f, -kPi / 2 + 0.15f, kPi / 2 - 0.15f, "handle"));
    return m;
}

PartMesh Bottle(StreamRng& rng) {
    const float r = U(rng, 0.03f, 0.045f), H = U(rng, 0.18f, 0.32f);
    const float rn = U(rng, 0.011f, 0.016f), rc = rn + 0.002f;
    std::vector<ProfilePoint> p{{0, 0, 0}, {r, 0, 0}, {r, 0.6f * H, 0}};
    for (int i = 1; i <= 6; ++i) {  // shoulder
        const float s = static_cast<float>(i) / 6;
        p.push_back(
            {rn + (r - rn) * std::cos(s * kPi / 2), (0.6f + 0.2f * s) * H, s < 1 ? 0u : 1u});
    }
    p.push_back({rn, 0.92f * H, 2});
    p.push_back({rc, 0.92f * H, 2});
    p.push_back({rc, H, 2});
    p.push_back({0, H, 2});
    return MakeRevolutionMesh(p, {"body", "neck", "cap"});
}

PartMesh Pitcher(StreamRng& rng) {
    const float rb = U(rng, 0.05f, 0.07f), h = U(rng, 0.15f, 0.24f);
    const float rm = rb * U(rng, 1.0f, 1.15f), rt = rb * U(rng, 0.75f, 0.9f), t = 0.004f;
    PartMesh m = MakeRevolutionMesh({{0, 0, 0},
                                     {rb, 0, 0},
                                     {rm, 0.4f * h, 0},
                                     {rt, h, 0},
                                     {rt - t, h, 0},
                                     {rm - t, 0.4f * h, 0},
                                     {rb - t, t, 0},
                                     {0, t, 0}},
                                    {"body"});
    const float arc = h * 0.3f;
    m.AppendParts(MakeHandle((rm + rt) / 2, 0.6f * h, arc, 0.008f, -kPi / 2 + 0.2f, kPi / 2 - 0.2f,
                             "handle"));
    return m;
}

PartMesh Irregular(StreamRng& rng) {
    // A sphere with random low-frequency bumps, stretched, its bottom cut flat to rest on.
    const float R = U(rng, 0.04f, 0.09f);
    const Eigen::Vector3f stretch(U(rng, 0.7f, 1.6f), U(rng, 0.6f, 1.2f), U(rng, 0.6f, 1.4f));
    float amp[3], fa[3], fb[3], ph[3];
    for (int k = 0; k < 3; ++k) {
        amp[k] = U(rng, 0.05f, 0.2f);
        fa[k] = static_cast<float>(rng.UniformInt(1, 3));
        fb[k] = static_cast<float>(rng.UniformInt(1, 3));
        ph[k] = U(rng, 0.0f, 2 * kPi);
    }
    const int rings = 16, seg = 24;
    TriangleMesh m;
    for (int i = 0; i <= rings; ++i) {
        const float th = kPi * static_cast<float>(i) / rings;
        for (int j = 0; j < seg; ++j) {
            const float phi = 2 * kPi * static_cast<float>(j) / seg;
            float s = 1.0f;
            for (int k = 0; k < 3; ++k)
                s += amp[k] * std::sin(fa[k] * th + ph[k]) * std::cos(fb[k] * phi);
            const Eigen::Vector3f dir(std::sin(th) * std::cos(phi), std::sin(th) * std::sin(phi),
                                      std::cos(th));
            m.vertices.push_back(R * s * dir.cwiseProduct(stretch));
        }
    }
    for (int i = 0; i < rings; ++i) {
        for (int j = 0; j < seg; ++j) {
            const auto a = static_cast<std::uint32_t>(i * seg + j);
            const auto b = static_cast<std::uint32_t>(i * seg + (j + 1) % seg);
            m.triangles.emplace_back(a, a + seg, b);
            m.triangles.emplace_back(b, a + seg, b + seg);
        }
    }
    float zmin = 1e9f;
    for (const auto& v : m.vertices) zmin = std::min(zmin, v.z());
    const float cut = zmin + 0.2f * R;
    for (auto& v : m.vertices) v.z() = std::max(v.z(), cut) - cut;
    return Single(std::move(m), "body");
}

}  // namespace

PartMesh MakeBoxMesh(const Eigen::Vector3f& e, const std::string& part) {
    TriangleMesh m;
    for (int i = 0; i < 8; ++i) {
        m.vertices.emplace_back((i & 1 ? 0.5f : -0.5f) * e.x(), (i & 2 ? 0.5f : -0.5f) * e.y(),
                                (i & 4 ? 1.0f : 0.0f) * e.z());
    }
    const int f[12][3] = {{0, 2, 1}, {1, 2, 3}, {4, 5, 6}, {5, 7, 6}, {0, 1, 4}, {1, 5, 4},
                          {2, 6, 3}, {3, 6, 7}, {0, 4, 2}, {2, 4, 6}, {1, 3, 5}, {3, 7, 5}};
    for (const auto& t : f) {
        m.triangles.emplace_back(static_cast<std::uint32_t>(t[0]), static_cast<std::uint32_t>(t[1]),
                                 static_cast<std::uint32_t>(t[2]));
    }
    return Single(std::move(m), part);
}

PartMesh MakeRevolutionMesh(const std::vector<ProfilePoint>& profile,
                            const std::vector<std::string>& parts, int segments) {
    if (profile.size() < 2 || segments < 3) {
        throw InvalidArgument(
            fmt::format("revolution needs >= 2 profile points and >= 3 segments, got {} and {}",
                        profile.size(), segments));
    }
    PartMesh pm;
    pm.part_names = parts;
    auto& m = pm.mesh;
    const auto S = static_cast<std::uint32_t>(segments);
    std::vector<std::uint32_t> first;  // first vertex of each ring
    std::vector<bool> pole;
    for (const auto& p : profile) {
        first.push_back(static_cast<std::uint32_t>(m.vertices.size()));
        pole.push_back(p.r <= 1e-7f);
        if (pole.back()) {
            m.vertices.emplace_back(0.0f, 0.0f, p.z);
            continue;
        }
        for (std::uint32_t j = 0; j < S; ++j) {
            const float a = 2 * kPi * static_cast<float>(j) / static_cast<float>(S);
            m.vertices.emplace_back(p.r * std::cos(a), p.r * std::sin(a), p.z);
        }
    }
    for (std::size_t k = 0; k + 1 < profile.size(); ++k) {
        const std::uint32_t part =
            std::min<std::uint32_t>(profile[k].part, static_cast<std::uint32_t>(parts.size() - 1));
        const std::uint32_t a0 = first[k], b0 = first[k + 1];
        for (std::uint32_t j = 0; j < S; ++j) {
            const std::uint32_t jn = (j + 1) % S;
            if (pole[k] && pole[k + 1]) break;
            if (pole[k]) {
                m.triangles.emplace_back(a0, b0 + jn, b0 + j);
                pm.triangle_parts.push_back(part);
            } else if (pole[k + 1]) {
                m.triangles.emplace_back(a0 + j, a0 + jn, b0);
                pm.triangle_parts.push_back(part);
            } else {
                m.triangles.emplace_back(a0 + j, a0 + jn, b0 + jn);
                m.triangles.emplace_back(a0 + j, b0 + jn, b0 + j);
                pm.triangle_parts.push_back(part);
                pm.triangle_parts.push_back(part);
            }
        }
    }
    return pm;
}

const std::vector<std::pair<std::string, std::string>>& ProceduralKinds() {
    static const std::vector<std::pair<std::string, std::string>> kinds = {
        {"ball", "sphere"},     {"bowl", "sphere"},  {"box", "box"},       {"flat_box", "flat"},
        {"can", "cylinder"},    {"cup", "cylinder"}, {"mug", "cylinder"},  {"tin", "cylinder"},
        {"bottle", "cylinder"}, {"plate", "plate"},  {"pitcher", "other"}, {"irregular", "other"}};
    return kinds;
}

ProceduralObject MakeProceduralKind(const std::string& kind, StreamRng& rng) {
    ProceduralObject o;
    o.kind = kind;
    if (kind == "ball") {
        o.mesh = Ball(rng);
    } else if (kind == "bowl") {
        o.mesh = Bowl(rng, o.cavity);
    } else if (kind == "box") {
        // Compact: the smallest side at least 35 % of the largest.
        const float L = U(rng, 0.08f, 0.22f);
        o.mesh = MakeBoxMesh({L, L * U(rng, 0.4f, 1.0f), L * U(rng, 0.35f, 1.0f)});
    } else if (kind == "flat_box") {
        // Cereal boxes, books, thin food boxes: one side under a third of the middle one.
        const float L = U(rng, 0.14f, 0.33f), M = L * U(rng, 0.5f, 0.85f);
        const float T = std::clamp(M * U(rng, 0.12f, 0.3f), 0.015f, 0.08f);
        o.mesh = MakeBoxMesh({L, M, T});
    } else if (kind == "can") {
        o.mesh = Can(rng);
    } else if (kind == "cup") {
        const float rb = U(rng, 0.025f, 0.04f);
        o.mesh = Cup(rb, rb * U(rng, 1.0f, 1.25f), U(rng, 0.07f, 0.12f), 0.003f);
    } else if (kind == "tin") {
        // Biscuit and cake tins, plastic tubs upside down: wide and low.
        const float r = U(rng, 0.065f, 0.1f), h = U(rng, 0.06f, 0.12f);
        o.mesh = MakeRevolutionMesh({{0, 0, 0}, {r, 0, 1}, {r, h, 2}, {0, h, 2}},
                                    {"bottom", "body", "top"});
    } else if (kind == "mug") {
        o.mesh = Mug(rng);
    } else if (kind == "bottle") {
        o.mesh = Bottle(rng);
    } else if (kind == "plate") {
        o.mesh = Plate(rng, o.cavity);
    } else if (kind == "pitcher") {
        o.mesh = Pitcher(rng);
    } else if (kind == "irregular") {
        o.mesh = Irregular(rng);
    } else {
        throw InvalidArgument(fmt::format("unknown procedural object kind '{}'", kind));
    }
    for (const auto& [k, c] : ProceduralKinds()) {
        if (k == kind) o.category = c;
    }
    o.mesh.name = kind;
    return o;
}

ProceduralObject MakeProceduralObject(const std::string& category, StreamRng& rng) {
    std::vector<std::string> kinds;
    for (const auto& [k, c] : ProceduralKinds()) {
        if (c == category) kinds.push_back(k);
    }
    if (kinds.empty()) {
        throw InvalidArgument(fmt::format(
            "unknown category '{}' (expected sphere, box, flat, cylinder, plate or other)",
            category));
    }
    const auto pick =
        static_cast<std::size_t>(rng.UniformInt(0, static_cast<int>(kinds.size()) - 1));
    return MakeProceduralKind(kinds[pick], rng);
}

}  // namespace multicue::sim
