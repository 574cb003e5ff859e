#include "multicue/sim/objects.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include <fmt/format.h>
#include <fmt/ranges.h>
#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>

#include "multicue/core/exceptions.hpp"
#include "multicue/sim/procedural.hpp"

namespace multicue::sim {
namespace {

constexpr float kMinTipAngle = 12.0f * static_cast<float>(M_PI) / 180.0f;

float Cross(const Eigen::Vector2f& o, const Eigen::Vector2f& a, const Eigen::Vector2f& b) {
    return (a.x() - o.x()) * (b.y() - o.y()) - (a.y() - o.y()) * (b.x() - o.x());
}

/// Rotation taking unit vector `down` (object frame) to world -z.
Eigen::Matrix3f RotationDown(const Eigen::Vector3f& down) {
    return Eigen::Quaternionf::FromTwoVectors(down, -Eigen::Vector3f::UnitZ()).toRotationMatrix();
}

bool StableAlong(const PartMesh& pm, const Eigen::Vector3f& centroid, const Eigen::Vector3f& down) {
    const auto& V = pm.mesh.vertices;
    float lowest = -std::numeric_limits<float>::infinity();
    for (const auto& v : V) lowest = std::max(lowest, v.dot(down));
    // Basis of the plane perpendicular to `down`.
    const Eigen::Vector3f e1 = down.unitOrthogonal(), e2 = down.cross(e1);
    std::vector<Eigen::Vector2f> contact;
    for (const auto& v : V) {
        if (v.dot(down) >= lowest - 5e-4f) contact.emplace_back(v.dot(e1), v.dot(e2));
    }
    const auto hull = ConvexHull2D(contact);
    if (hull.size() < 3) return false;
    const Eigen::Vector2f c(centroid.dot(e1), centroid.dot(e2));
    float inside = std::numeric_limits<float>::infinity();  // distance to the nearest hull edge
    for (std::size_t i = 0; i < hull.size(); ++i) {
        const Eigen::Vector2f& a = hull[i];
        const Eigen::Vector2f& b = hull[(i + 1) % hull.size()];
        // Counter-clockwise hull: the inside is on the left of every edge.
        inside = std::min(inside, Cross(a, b, c) / std::max((b - a).norm(), 1e-9f));
    }
    // Stable when tipping over needs at least kMinTipAngle: excludes rolling (cylinders on their
    // side, balls) and poses a touch would topple (a bottle on its cap, a book on its edge).
    const float height = lowest - centroid.dot(down);
    return inside > 0.0f && std::atan2(inside, std::max(height, 1e-6f)) >= kMinTipAngle;
}

}  // namespace

std::vector<Eigen::Vector2f> ConvexHull2D(std::vector<Eigen::Vector2f> p) {
    std::sort(p.begin(), p.end(), [](const auto& a, const auto& b) {
        return a.x() < b.x() || (a.x() == b.x() && a.y() < b.y());
    });
    p.erase(std::unique(p.begin(), p.end()), p.end());
    if (p.size() < 3) return p;
    std::vector<Eigen::Vector2f> h(2 * p.size());
    std::size_t k = 0;
    for (std::size_t i = 0; i < p.size(); ++i) {
        while (k >= 2 && Cross(h[k - 2], h[k - 1], p[i]) <= 0) --k;
        h[k++] = p[i];
    }
    for (std::size_t i = p.size() - 1, t = k + 1; i > 0; --i) {
        while (k >= t && Cross(h[k - 2], h[k - 1], p[i - 1]) <= 0) --k;
        h[k++] = p[i - 1];
    }
    h.resize(k - 1);
    return h;
}

float PolygonSeparation(const std::vector<Eigen::Vector2f>& a,
                        const std::vector<Eigen::Vector2f>& b) {
    float best = -std::numeric_limits<float>::infinity();
    for (const auto* poly : {&a, &b}) {
        for (std::size_t i = 0; i < poly->size(); ++i) {
            const Eigen::Vector2f e = (*poly)[(i + 1) % poly->size()] - (*poly)[i];
            if (e.squaredNorm() < 1e-12f) continue;
            const Eigen::Vector2f n = Eigen::Vector2f(e.y(), -e.x()).normalized();
            float amin = std::numeric_limits<float>::infinity(), amax = -amin;
            float bmin = amin, bmax = -amin;
            for (const auto& q : a) {
                amin = std::min(amin, q.dot(n));
                amax = std::max(amax, q.dot(n));
            }
            for (const auto& q : b) {
                bmin = std::min(bmin, q.dot(n));
                bmax = std::max(bmax, q.dot(n));
            }
            best = std::max(best, std::max(bmin - amax, amin - bmax));
        }
    }
    return best;
}

std::vector<Eigen::Matrix3f> StableRotations(const PartMesh& pm) {
    const auto& V = pm.mesh.vertices;
    const auto& T = pm.mesh.triangles;
    // Surface centroid (area weighted): a hollow object's centre of mass.
    Eigen::Vector3f centroid = Eigen::Vector3f::Zero();
    float area = 0.0f;
    for (const auto& t : T) {
        const float a = 0.5f * (V[t[1]] - V[t[0]]).cross(V[t[2]] - V[t[0]]).norm();
        centroid += a * (V[t[0]] + V[t[1]] + V[t[2]]) / 3.0f;
        area += a;
    }
    if (area > 0.0f) centroid /= area;
    Eigen::Matrix3f cov = Eigen::Matrix3f::Zero();
    for (const auto& v : V) cov += (v - centroid) * (v - centroid).transpose();
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3f> eig(cov);
    std::vector<Eigen::Vector3f> downs = {-Eigen::Vector3f::UnitZ(), Eigen::Vector3f::UnitZ(),
                                          Eigen::Vector3f::UnitX(),  -Eigen::Vector3f::UnitX(),
                                          Eigen::Vector3f::UnitY(),  -Eigen::Vector3f::UnitY()};
    for (int k = 0; k < 3; ++k) {
        downs.push_back(eig.eigenvectors().col(k).normalized());
        downs.push_back(-eig.eigenvectors().col(k).normalized());
    }
    std::vector<Eigen::Vector3f> kept;
    std::vector<Eigen::Matrix3f> out;
    for (const auto& d : downs) {
        if (!d.allFinite()) continue;
        bool dup = false;
        for (const auto& k : kept) dup = dup || k.dot(d) > std::cos(0.1f);
        if (dup || !StableAlong(pm, centroid, d)) continue;
        kept.push_back(d);
        out.push_back(RotationDown(d));
    }
    if (out.empty()) out.push_back(Eigen::Matrix3f::Identity());  // nothing stable: upright
    return out;
}

Color RandomColor(StreamRng& rng) {
    const float h = static_cast<float>(rng.Uniform(0.0, 6.0));
    const float s = static_cast<float>(rng.Uniform(0.4, 1.0));
    const float v = static_cast<float>(rng.Uniform(0.45, 1.0));
    const int i = static_cast<int>(h) % 6;
    const float f = h - std::floor(h);
    const float p = v * (1 - s), q = v * (1 - s * f), t = v * (1 - s * (1 - f));
    float r = v, g = t, b = p;
    switch (i) {
        case 1:
            r = q, g = v, b = p;
            break;
        case 2:
            r = p, g = v, b = t;
            break;
        case 3:
            r = p, g = q, b = v;
            break;
        case 4:
            r = t, g = p, b = v;
            break;
        case 5:
            r = v, g = p, b = q;
            break;
        default:
            break;
    }
    auto c8 = [](float x) { return static_cast<std::uint8_t>(std::lround(x * 255.0f)); };
    return Color{c8(r), c8(g), c8(b), 255};
}

ObjectSource::ObjectSource(std::vector<std::string> categories)
    : categories_(std::move(categories)) {
    if (categories_.empty()) categories_ = TabletopCategories();
    for (const auto& c : categories_) {
        const auto& all = TabletopCategories();
        if (std::find(all.begin(), all.end(), c) == all.end()) {
            throw InvalidArgument(fmt::format("unknown object category '{}'", c));
        }
    }
}

ObjectSource::ObjectSource(std::vector<MeshEntry> library, bool strict)
    : library_(std::move(library)), strict_(strict) {
    if (library_.empty()) throw DataError("mesh library has no entries");
}

std::shared_ptr<const PartMesh> ObjectSource::Load(std::size_t i) {
    const auto it = cache_.find(i);
    if (it != cache_.end()) return it->second;
    const MeshEntry& e = library_.at(i);
    // Shrunk meshes are resized later; loosen the unit check for them.
    MeshLoadParams params{.scale = e.scale_to_m};
    auto mesh = TryLoadMesh(e.file, params, strict_);
    std::shared_ptr<const PartMesh> ptr;
    if (mesh) ptr = std::make_shared<const PartMesh>(std::move(*mesh));
    cache_.emplace(i, ptr);
    return ptr;
}

std::optional<ObjectModel> ObjectSource::FromEntry(std::size_t i, StreamRng& rng) {
    auto mesh = Load(i);
    if (!mesh) return std::nullopt;
    const MeshEntry& e = library_[i];
    ObjectModel m{mesh, e.category, e.file.filename().string(), e.scale_to_m};
    if (e.rescale) {
        const auto [lo, hi] = RealisticExtentRange(e.category);
        const float target = static_cast<float>(rng.Uniform(lo, hi));
        const float factor = target / mesh->Bounds().sizes().maxCoeff();
        auto scaled = std::make_shared<PartMesh>(*mesh);
        for (auto& v : scaled->mesh.vertices) v *= factor;
        m.mesh = scaled;
        m.scale = e.scale_to_m * factor;
    }
    return m;
}

ObjectModel ObjectSource::Random(StreamRng& rng) {
    if (!IsLibrary()) {
        const auto c =
            static_cast<std::size_t>(rng.UniformInt(0, static_cast<int>(categories_.size()) - 1));
        ProceduralObject o = MakeProceduralObject(categories_[c], rng);
        const std::string kind = o.kind;
        return ObjectModel{std::make_shared<const PartMesh>(std::move(o.mesh)), o.category, kind,
                           1.0f, std::move(o.cavity)};
    }
    for (int attempt = 0; attempt < 64; ++attempt) {
        const auto i =
            static_cast<std::size_t>(rng.UniformInt(0, static_cast<int>(library_.size()) - 1));
        if (auto m = FromEntry(i, rng)) return *m;
    }
    for (std::size_t i = 0; i < library_.size(); ++i) {
        if (auto m = FromEntry(i, rng)) return *m;
    }
    throw DataError("no mesh of the library could be loaded");
}

ObjectModel ObjectSource::RandomOf(const ObjectFilter& filter, StreamRng& rng) {
    if (!IsLibrary()) {
        if (filter.kinds.empty()) return Random(rng);
        const auto k =
            static_cast<std::size_t>(rng.UniformInt(0, static_cast<int>(filter.kinds.size()) - 1));
        ProceduralObject o = MakeProceduralKind(filter.kinds[k], rng);
        const std::string kind = o.kind;
        return ObjectModel{std::make_shared<const PartMesh>(std::move(o.mesh)), o.category, kind,
                           1.0f, std::move(o.cavity)};
    }
    if (filter.categories.empty()) return Random(rng);
    std::vector<std::size_t> entries;
    for (std::size_t i = 0; i < library_.size(); ++i) {
        const auto& c = filter.categories;
        if (std::find(c.begin(), c.end(), library_[i].category) != c.end()) entries.push_back(i);
    }
    for (int attempt = 0; attempt < 64 && !entries.empty(); ++attempt) {
        const auto i =
            static_cast<std::size_t>(rng.UniformInt(0, static_cast<int>(entries.size()) - 1));
        if (auto m = FromEntry(entries[i], rng)) return *m;
    }
    for (const std::size_t i : entries) {
        if (auto m = FromEntry(i, rng)) return *m;
    }
    throw DataError(fmt::format("no mesh of the categories {} could be loaded",
                                fmt::join(filter.categories, ", ")));
}

}  // namespace multicue::sim
