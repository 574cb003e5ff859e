// Table scenes of the mOSD-like modes (TableSceneMode other than kDefault): which objects each
// mode draws and how they are arranged (standing, touching, stacked, nested, leaning, in front of
// one another). Every placement is checked against everything already on the table.

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <numbers>

#include <fmt/format.h>

#include "multicue/core/exceptions.hpp"
#include "multicue/sim/placement_internal.hpp"
#include "multicue/sim/procedural.hpp"
#include "multicue/sim/scene_gen.hpp"
#include "multicue/sim/sim_math_internal.hpp"

namespace multicue::sim {
namespace {

using namespace placement_internal;

using math_internal::kObjectStream;
using math_internal::kPi;
constexpr float kContact = 5e-4f;        ///< footprints at least this far apart do not touch [m]
constexpr float kLeanContact = 2e-4f;    ///< gap a leaning object keeps to its support [m]
constexpr float kLevel = 1e-4f;          ///< z ranges overlapping less than this are stacked [m]
constexpr float kWallClearance = 2e-3f;  ///< nested objects keep this far from the wall [m]

constexpr std::array<std::pair<TableSceneMode, const char*>, 7> kModeNames = {{
    {TableSceneMode::kDefault, "default"},
    {TableSceneMode::kBoxes, "boxes"},
    {TableSceneMode::kStacked, "stacked"},
    {TableSceneMode::kOccluded, "occluded"},
    {TableSceneMode::kCylindric, "cylindric"},
    {TableSceneMode::kMixed, "mixed"},
    {TableSceneMode::kComplex, "complex"},
}};

// What a mode draws and how it arranges it.
struct Recipe {
    ObjectFilter objects;          ///< what the mode puts on the table (empty: everything)
    float stack = 0.0f;            ///< chance that an object is put on top of another
    float nest = 0.0f;             ///< chance that an object is put into a container
    float lean = 0.0f;             ///< chance that a flat object leans against another
    int max_levels = 1;            ///< objects per stack, the one on the table included
    bool pairs = false;            ///< objects come in pairs, one in front of the other (occluded)
    bool container_first = false;  ///< the first object is a bowl or a plate
    bool stack_early = false;      ///< objects go on top of others until one does
    float lying = 0.0f;            ///< chance of the pose on the largest face (flattest)
};

const std::vector<std::string> kBoxKinds{"box", "flat_box"};
const std::vector<std::string> kBoxCategories{"box", "flat"};
const std::vector<std::string> kCylindricKinds{"can",    "cup",   "mug", "tin",
                                               "bottle", "plate", "bowl"};
const std::vector<std::string> kCylindricCategories{"cylinder", "plate"};
// Objects small enough to go into a bowl or onto a plate, objects that lean, containers.
const ObjectFilter kNestable{{"ball", "irregular", "box", "can", "cup", "mug"},
                             {"sphere", "box", "cylinder", "other"}};
const ObjectFilter kLeaners{{"flat_box", "plate"}, {"flat", "plate"}};
const ObjectFilter kContainers{{"bowl", "plate"}, {"sphere", "plate"}};

std::vector<std::string> Concat(std::vector<std::string> a, const std::vector<std::string>& b) {
    a.insert(a.end(), b.begin(), b.end());
    return a;
}

Recipe RecipeFor(TableSceneMode mode) {
    Recipe r;
    switch (mode) {
        case TableSceneMode::kBoxes:
            r.objects = {kBoxKinds, kBoxCategories};
            break;
        case TableSceneMode::kStacked:
            r.objects = {kBoxKinds, kBoxCategories};
            r.stack = 0.6f;
            r.max_levels = 3;
            r.stack_early = true;
            r.lying = 0.7f;
            break;
        case TableSceneMode::kOccluded:
            // Everything that stands high enough to hide something: no plates.
            r.objects = {{"ball", "bowl", "box", "flat_box", "can", "cup", "mug", "tin", "bottle",
                          "pitcher", "irregular"},
                         {"sphere", "box", "flat", "cylinder", "other"}};
            r.pairs = true;
            break;
        case TableSceneMode::kCylindric:
            r.objects = {kCylindricKinds, kCylindricCategories};
            break;
        case TableSceneMode::kMixed:
            r.objects = {Concat(kBoxKinds, kCylindricKinds),
                         Concat(kBoxCategories, kCylindricCategories)};
            r.stack = 0.15f;
            r.max_levels = 2;
            break;
        case TableSceneMode::kComplex:
            r.stack = 0.2f;
            r.nest = 0.15f;
            r.lean = 0.12f;
            r.max_levels = 3;
            r.container_first = true;
            break;
        case TableSceneMode::kDefault:
            break;
    }
    return r;
}

float Area(const Polygon& p) {
    float a = 0.0f;
    for (std::size_t i = 0; i < p.size(); ++i) {
        const auto& u = p[i];
        const auto& v = p[(i + 1) % p.size()];
        a += u.x() * v.y() - v.x() * u.y();
    }
    return 0.5f * a;
}

/// Distance of `q` from the boundary of the counter-clockwise convex polygon `p`, positive inside.
float InsideDistance(const Polygon& p, const Eigen::Vector2f& q) {
    if (p.size() < 3) return -std::numeric_limits<float>::infinity();
    float d = std::numeric_limits<float>::infinity();
    for (std::size_t i = 0; i < p.size(); ++i) {
        const Eigen::Vector2f e = p[(i + 1) % p.size()] - p[i];
        const Eigen::Vector2f w = q - p[i];
        d = std::min(d, (e.x() * w.y() - e.y() * w.x()) / std::max(e.norm(), 1e-9f));
    }
    return d;
}

Eigen::Vector2f BoxCentre(const Polygon& p) {
    Eigen::Vector2f lo = p.front(), hi = p.front();
    for (const auto& q : p) {
        lo = lo.cwiseMin(q);
        hi = hi.cwiseMax(q);
    }
    return (lo + hi) / 2;
}

/// Radius of a container's inner wall (ObjectModel::cavity) at height z above its base.
float WallRadius(const std::vector<Eigen::Vector2f>& cavity, float z) {
    if (z <= cavity.front().y()) return cavity.front().x();
    for (std::size_t i = 0; i + 1 < cavity.size(); ++i) {
        const auto& a = cavity[i];
        const auto& b = cavity[i + 1];
        if (z <= b.y())
            return a.x() + (b.x() - a.x()) * (z - a.y()) / std::max(b.y() - a.y(), 1e-9f);
    }
    return cavity.back().x();  // above the rim: the rim's cylinder
}

/// Objects with a flat, closed top and vertical sides in every stable pose: things stand on
/// them and lean against them.
bool IsBlock(const ObjectModel& m) {
    for (const char* kind : {"box", "flat_box", "can", "tin"}) {
        if (m.source == kind) return true;
    }
    for (const auto& [kind, category] : ProceduralKinds()) {
        if (m.source == kind) return false;
    }
    return m.category == "box" || m.category == "flat";
}

/// An object about to be placed: its pose resting at height 0 and its vertices in that pose
/// relative to the footprint centre.
struct Candidate {
    ObjectModel model;
    Pose pose;
    std::vector<Eigen::Vector3f> vertices;
    float height = 0.0f;
    float mass = 0.0f;  ///< bounding-box volume, the weight in centre-of-mass sums

    Candidate(ObjectModel m, Pose p) : model(std::move(m)), pose(std::move(p)) {
        Eigen::AlignedBox3f box;
        for (const auto& v : model.mesh->mesh.vertices) {
            vertices.push_back(pose.R * v +
                               Eigen::Vector3f(pose.offset.x(), pose.offset.y(), pose.z));
            box.extend(vertices.back());
        }
        height = box.max().z() - box.min().z();
        mass = box.volume();
    }

    /// Convex hull in x-y of the part of the object between heights z0 and z1 when it rests at
    /// height h (vertices in the band and the crossings of the mesh edges with its planes).
    Polygon Slice(float h, float z0, float z1) const {
        Polygon pts;
        const float a = z0 - h, b = z1 - h;
        for (const auto& v : vertices) {
            if (v.z() >= a && v.z() <= b) pts.emplace_back(v.x(), v.y());
        }
        for (const auto& t : model.mesh->mesh.triangles) {
            for (int e = 0; e < 3; ++e) {
                const Eigen::Vector3f& p = vertices[t[e]];
                const Eigen::Vector3f& q = vertices[t[(e + 1) % 3]];
                for (const float z : {a, b}) {
                    if ((p.z() - z) * (q.z() - z) < 0.0f) {
                        const float s = (z - p.z()) / (q.z() - p.z());
                        pts.push_back((p + s * (q - p)).head<2>());
                    }
                }
            }
        }
        return ConvexHull2D(std::move(pts));
    }
};

/// A placed object as the composer sees it: a vertical prism around it (its footprint between
/// its lowest and highest point) and what it offers to the objects placed after it.
struct Body {
    std::uint32_t label = 0;
    ObjectPlacement placement = ObjectPlacement::kStanding;
    Polygon footprint;
    float zmin = 0.0f, zmax = 0.0f;
    int support = -1;    ///< body it rests on, sits in or leans against; -1: the table
    int level = 0;       ///< 0 on the table, 1 on a table-level object, ...
    Polygon top;         ///< flat top face in x-y; empty: nothing stands on it
    bool block = false;  ///< the prism is its shape: objects may lean on it
    std::vector<Eigen::Vector2f> cavity;             ///< upright container: inner wall; else empty
    Eigen::Vector2f axis = Eigen::Vector2f::Zero();  ///< container axis in x-y
    bool occupied = false;                           ///< holds an object or has one leaning on it
    float mass = 0.0f;
    Eigen::Vector2f centre = Eigen::Vector2f::Zero();
};

class Composer {
  public:
    Composer(const TableSceneParams& p, ObjectSource& source, std::uint64_t seed)
        : p_(p), source_(source), seed_(seed) {
        // The table as in the default mode (same draws from stream 0).
        StreamRng rng(seed, 0);
        h_ = AddTableAndFloor(p, rng, scene_);
        const Eigen::Vector2f size = scene_.support_size;
        lo_ = -size / 2 + Eigen::Vector2f::Constant(p.edge_margin);
        hi_ = size / 2 - Eigen::Vector2f::Constant(p.edge_margin);
        count_ = rng.UniformInt(p.min_objects, p.max_objects);
        // Seen from one of the long sides (x is the long axis), as a robot at a table would.
        const float side = rng.Uniform() < 0.5 ? kPi / 2 : -kPi / 2;
        scene_.view_azimuth = side + static_cast<float>(rng.Uniform(-0.3, 0.3));
        camera_ = Eigen::Vector2f(std::cos(scene_.view_azimuth), std::sin(scene_.view_azimuth));
    }

    Scene Compose() {
        const Recipe r = RecipeFor(p_.mode);
        // Each object has its own stream: adding an object never changes the ones before it.
        // Streams of objects that found no place are skipped, up to a limit.
        std::uint64_t k = 0;
        const auto streams = static_cast<std::uint64_t>(4 * count_ + 8);
        while (static_cast<int>(bodies_.size()) < count_ && k < streams) {
            if (r.pairs && count_ - static_cast<int>(bodies_.size()) >= 2) {
                PlacePair(r, k);
                k += 2;
            } else {
                PlaceOne(r, k++);
            }
        }
        return std::move(scene_);
    }

  private:
    StreamRng Stream(std::uint64_t k) const { return StreamRng(seed_, kObjectStream + k); }

    Candidate Draw(const ObjectFilter& filter, StreamRng& rng, Color& color,
                   float upright_probability, float lying = 0.0f) {
        ObjectModel model = source_.RandomOf(filter, rng);
        color = RandomColor(rng);
        if (rng.Uniform() < lying) return Candidate(model, LyingPose(*model.mesh, rng));
        Pose pose = ChoosePose(*model.mesh, 0.0f, upright_probability, rng);
        return Candidate(std::move(model), std::move(pose));
    }

    /// The stable pose of least height (a box on its largest face) with a random yaw.
    static Pose LyingPose(const PartMesh& mesh, StreamRng& rng) {
        Eigen::Matrix3f best = Eigen::Matrix3f::Identity();
        float lowest = std::numeric_limits<float>::infinity();
        for (const auto& R : StableRotations(mesh)) {
            float zmin = std::numeric_limits<float>::infinity(), zmax = -zmin;
            for (const auto& v : mesh.mesh.vertices) {
                const float z = R.row(2).dot(v);
                zmin = std::min(zmin, z);
                zmax = std::max(zmax, z);
            }
            if (zmax - zmin < lowest - 1e-6f) {
                lowest = zmax - zmin;
                best = R;
            }
        }
        const float yaw = static_cast<float>(rng.Uniform(0.0, 2.0 * kPi));
        return RestingPose(
            mesh, Eigen::AngleAxisf(yaw, Eigen::Vector3f::UnitZ()).toRotationMatrix() * best, 0.0f);
    }

    /// One object of stream k, placed as the recipe draws it, falling back to standing.
    void PlaceOne(const Recipe& r, std::uint64_t k) {
        StreamRng rng = Stream(k);
        const double pick = rng.Uniform();
        const bool touch = rng.Uniform() < p_.clutter;
        Color color;
        const std::size_t n = bodies_.size();
        if (r.container_first && n == 0) {
            const Candidate c = Draw(kContainers, rng, color, 1.0f);
            Standing(c, rng, false, color, false);
        } else if ((r.container_first && n == 1) || pick < r.nest) {
            const Candidate c = Draw(kNestable, rng, color, p_.upright_probability);
            if (!Nested(c, rng, color)) Standing(c, rng, touch, color, false);
        } else if (pick < r.nest + r.lean) {
            ObjectModel model = source_.RandomOf(kLeaners, rng);
            color = RandomColor(rng);
            if (!Leaning(model, rng, color)) {
                const Candidate c(model, ChoosePose(*model.mesh, 0.0f, 1.0f, rng));
                Standing(c, rng, touch, color, false);
            }
        } else {
            const Candidate c = Draw(r.objects, rng, color, p_.upright_probability, r.lying);
            const bool stack =
                (r.stack_early && n >= 1 && !stacked_) || pick < r.nest + r.lean + r.stack;
            if (stack && Stacked(c, rng, r.max_levels, color)) return;
            if (Standing(c, rng, touch, color, false)) return;
            if (r.max_levels > 1) Stacked(c, rng, r.max_levels, color);
        }
    }

    /// Two objects of streams k and k + 1: the taller one stands in the half of the table away
    /// from the camera, the other in front of it, shifted sideways, so it hides part of it.
    void PlacePair(const Recipe& r, std::uint64_t k) {
        StreamRng rng_a = Stream(k), rng_b = Stream(k + 1);
        Color color_a, color_b;
        // At least 6 cm high and of similar height, so that the front one hides a good part of
        // the other (a few redraws from the same streams).
        Candidate a = Draw(r.objects, rng_a, color_a, p_.upright_probability);
        for (int redraw = 0; redraw < 6 && a.height < 0.06f; ++redraw) {
            a = Draw(r.objects, rng_a, color_a, p_.upright_probability);
        }
        Candidate b = Draw(r.objects, rng_b, color_b, p_.upright_probability);
        for (int redraw = 0; redraw < 6; ++redraw) {
            if (b.height >= 0.06f &&
                std::min(a.height, b.height) >= 0.5f * std::max(a.height, b.height)) {
                break;
            }
            b = Draw(r.objects, rng_b, color_b, p_.upright_probability);
        }
        const bool a_back = a.height >= b.height;
        const Candidate& back = a_back ? a : b;
        const Candidate& front = a_back ? b : a;
        StreamRng& rng_back = a_back ? rng_a : rng_b;
        StreamRng& rng_front = a_back ? rng_b : rng_a;
        if (!Standing(back, rng_back, false, a_back ? color_a : color_b, true) &&
            !Standing(back, rng_back, false, a_back ? color_a : color_b, false)) {
            return;
        }
        const Color front_color = a_back ? color_b : color_a;
        if (!InFront(front, static_cast<int>(bodies_.size()) - 1, rng_front, front_color)) {
            Standing(front, rng_front, false, front_color, false);
        }
    }

    /// True when nothing but body `ignore` is within `gap` of the prism (fp, zmin..zmax).
    bool Clear(const Polygon& fp, float zmin, float zmax, float gap, int ignore = -1) const {
        for (std::size_t i = 0; i < bodies_.size(); ++i) {
            const Body& b = bodies_[i];
            if (static_cast<int>(i) == ignore) continue;
            if (std::min(zmax, b.zmax) - std::max(zmin, b.zmin) <= kLevel) continue;
            if (PolygonSeparation(fp, b.footprint) < gap) return false;
        }
        return true;
    }

    /// Clear for a tilted object: against blocks its slice in their height range is tested.
    bool ClearSliced(const Candidate& c, const Eigen::Vector2f& at, int ignore) const {
        const Polygon fp = Translated(c.pose.footprint, at);
        for (std::size_t i = 0; i < bodies_.size(); ++i) {
            const Body& b = bodies_[i];
            if (static_cast<int>(i) == ignore) continue;
            if (std::min(h_ + c.height, b.zmax) - std::max(h_, b.zmin) <= kLevel) continue;
            const Polygon shape =
                b.block ? Translated(c.Slice(h_, b.zmin + kLevel, b.zmax - kLevel), at) : fp;
            if (shape.size() >= 3 && PolygonSeparation(shape, b.footprint) < kContact) return false;
        }
        return true;
    }

    void Add(const Candidate& c, const Eigen::Vector2f& at, float h, ObjectPlacement placement,
             int support, Color color) {
        Pose pose = c.pose;
        pose.z += h;
        Body b;
        b.label = ObjectLabel(static_cast<std::uint32_t>(bodies_.size() + 1));
        scene_.objects.push_back(MakeInstance(c.model, pose, at, b.label, color));
        scene_.objects.back().placement = placement;
        scene_.objects.back().support =
            support < 0 ? kTableLabel : bodies_[static_cast<std::size_t>(support)].label;
        b.footprint = Translated(c.pose.footprint, at);
        b.zmin = h;
        b.zmax = h + c.height;
        b.support = support;
        b.placement = placement;
        b.level = support >= 0 && placement == ObjectPlacement::kStacked
                      ? bodies_[static_cast<std::size_t>(support)].level + 1
                      : 0;
        b.mass = c.mass;
        b.centre = at;
        const bool upright = pose.R(2, 2) > 0.9999f;
        if (placement != ObjectPlacement::kLeaning && placement != ObjectPlacement::kNested) {
            b.block = IsBlock(c.model);
            if (b.block) {
                // The top face: vertices within 1 mm of the highest point, or within up to 4 mm
                // (3 % of the height) for scanned meshes whose tops are not quite flat; what is
                // put on it rests at the highest point, so it never sinks in.
                const float band = std::max(1e-3f, std::min(4e-3f, 0.03f * c.height));
                Polygon top;
                for (const auto& v : c.vertices) {
                    if (v.z() >= c.height - band) top.push_back(v.head<2>() + at);
                }
                top = ConvexHull2D(std::move(top));
                if (top.size() >= 3 && Area(top) >= 0.3f * Area(b.footprint)) b.top = top;
            }
            if (!c.model.cavity.empty() && upright) {
                b.cavity = c.model.cavity;
                b.axis = at + pose.offset;
            }
        }
        bodies_.push_back(std::move(b));
        stacked_ = stacked_ || placement == ObjectPlacement::kStacked;
    }

    /// On the table, apart from everything (at least min_gap) or touching a table-level object;
    /// `back`: only in the half of the table away from the camera.
    bool Standing(const Candidate& c, StreamRng& rng, bool touch, Color color, bool back) {
        std::vector<int> ground;
        for (std::size_t i = 0; i < bodies_.size(); ++i) {
            const Body& b = bodies_[i];
            if (b.support < 0 || b.placement == ObjectPlacement::kLeaning) {
                ground.push_back(static_cast<int>(i));
            }
        }
        touch = touch && !ground.empty();
        for (int tries = 0; tries < 60; ++tries) {
            Eigen::Vector2f at;
            if (touch) {
                const Body& j = bodies_[static_cast<std::size_t>(ground[static_cast<std::size_t>(
                    rng.UniformInt(0, static_cast<int>(ground.size()) - 1))])];
                const float a = static_cast<float>(rng.Uniform(0.0, 2.0 * kPi));
                const Eigen::Vector2f dir(std::cos(a), std::sin(a));
                float s_lo = 0.0f, s_hi = 1.5f;  // overlapping .. apart
                for (int it = 0; it < 24; ++it) {
                    const float s = (s_lo + s_hi) / 2;
                    const auto poly = Translated(c.pose.footprint, j.centre + s * dir);
                    (PolygonSeparation(poly, j.footprint) < 1e-3f ? s_lo : s_hi) = s;
                }
                at = j.centre + s_hi * dir;
            } else {
                at = Eigen::Vector2f(static_cast<float>(rng.Uniform(lo_.x(), hi_.x())),
                                     static_cast<float>(rng.Uniform(lo_.y(), hi_.y())));
                if (back && at.dot(camera_) > 0.0f) continue;
            }
            const auto fp = Translated(c.pose.footprint, at);
            if (!Inside(fp, lo_, hi_) ||
                !Clear(fp, h_, h_ + c.height, touch ? kContact : p_.min_gap)) {
                continue;
            }
            Add(c, at, h_, touch ? ObjectPlacement::kTouching : ObjectPlacement::kStanding, -1,
                color);
            return true;
        }
        return false;
    }

    /// True when the objects stacked on body `s`, with a new one of `mass` at `at`, stand: the
    /// new one's centre lies well inside the top face of `s`, and at every level down to the
    /// table the centre of mass of everything above lies on the top face below it.
    bool Stands(int s, const Eigen::Vector2f& at, float mass) const {
        for (int a = s; a >= 0; a = bodies_[static_cast<std::size_t>(a)].support) {
            const Body& base = bodies_[static_cast<std::size_t>(a)];
            Eigen::Vector2f com = mass * at;
            float total = mass;
            for (const Body& b : bodies_) {
                // b is above `a` when a chain of stacked objects leads from b down to it.
                for (const Body* x = &b; x->placement == ObjectPlacement::kStacked;
                     x = &bodies_[static_cast<std::size_t>(x->support)]) {
                    if (x->support != a) continue;
                    com += b.mass * b.centre;
                    total += b.mass;
                    break;
                }
            }
            com /= total;
            if (a == s) {
                // The new object itself stands well inside the top it rests on.
                Eigen::Vector2f lo = base.top.front(), hi = base.top.front();
                for (const auto& q : base.top) {
                    lo = lo.cwiseMin(q);
                    hi = hi.cwiseMax(q);
                }
                const float margin = std::max(0.01f, 0.15f * (hi - lo).minCoeff());
                if (InsideDistance(base.top, at) < margin) return false;
            }
            if (InsideDistance(base.top, com) < 0.005f) return false;
            if (base.level == 0) break;
        }
        return true;
    }

    /// On the flat top face of a block with fewer than max_levels - 1 objects below it.
    bool Stacked(const Candidate& c, StreamRng& rng, int max_levels, Color color) {
        std::vector<int> bases;
        for (std::size_t i = 0; i < bodies_.size(); ++i) {
            const Body& b = bodies_[i];
            if (!b.top.empty() && b.level + 1 < max_levels) bases.push_back(static_cast<int>(i));
        }
        if (bases.empty()) return false;
        for (int tries = 0; tries < 40; ++tries) {
            const int s = bases[static_cast<std::size_t>(
                rng.UniformInt(0, static_cast<int>(bases.size()) - 1))];
            const Body& base = bodies_[static_cast<std::size_t>(s)];
            Eigen::Vector2f lo = base.top.front(), hi = base.top.front();
            for (const auto& q : base.top) {
                lo = lo.cwiseMin(q);
                hi = hi.cwiseMax(q);
            }
            const Eigen::Vector2f at =
                BoxCentre(base.top) +
                Eigen::Vector2f(static_cast<float>(rng.Uniform(-0.25, 0.25)) * (hi.x() - lo.x()),
                                static_cast<float>(rng.Uniform(-0.25, 0.25)) * (hi.y() - lo.y()));
            const auto fp = Translated(c.pose.footprint, at);
            if (Area(fp) > 1.5f * Area(base.top) || !Stands(s, at, c.mass)) continue;
            if (!Inside(fp, lo_, hi_) || !Clear(fp, base.zmax, base.zmax + c.height, kContact)) {
                continue;
            }
            Add(c, at, base.zmax, ObjectPlacement::kStacked, s, color);
            return true;
        }
        return false;
    }

    /// On the floor of an upright container (bowl, plate), every vertex inside its inner wall or
    /// above it within the rim.
    bool Nested(const Candidate& c, StreamRng& rng, Color color) {
        std::vector<int> containers;
        for (std::size_t i = 0; i < bodies_.size(); ++i) {
            if (!bodies_[i].cavity.empty() && !bodies_[i].occupied) {
                containers.push_back(static_cast<int>(i));
            }
        }
        if (containers.empty()) return false;
        for (int tries = 0; tries < 40; ++tries) {
            const int k = containers[static_cast<std::size_t>(
                rng.UniformInt(0, static_cast<int>(containers.size()) - 1))];
            const Body& box = bodies_[static_cast<std::size_t>(k)];
            const float floor_z = box.zmin + box.cavity.front().y();
            const float r =
                0.7f * box.cavity.front().x() * static_cast<float>(std::sqrt(rng.Uniform()));
            const float a = static_cast<float>(rng.Uniform(0.0, 2.0 * kPi));
            const Eigen::Vector2f at = box.axis + r * Eigen::Vector2f(std::cos(a), std::sin(a));
            bool fits = true;
            for (const auto& v : c.vertices) {
                const Eigen::Vector2f radial = v.head<2>() + at - box.axis;
                const float z = v.z() + floor_z - box.zmin;
                if (radial.norm() > WallRadius(box.cavity, z) - kWallClearance) {
                    fits = false;
                    break;
                }
            }
            const auto fp = Translated(c.pose.footprint, at);
            if (!fits || !Clear(fp, floor_z, floor_z + c.height, kContact, k)) continue;
            Add(c, at, floor_z, ObjectPlacement::kNested, k, color);
            bodies_[static_cast<std::size_t>(k)].occupied = true;
            return true;
        }
        return false;
    }

    /// A flat object (flat box, plate) standing on one edge, tilted by 10-25 degrees towards a
    /// table-level block and slid towards it until it touches it: its top edge rests on the
    /// block's side or its face on the block's top edge.
    bool Leaning(const ObjectModel& model, StreamRng& rng, Color color) {
        std::vector<int> supports;
        for (std::size_t i = 0; i < bodies_.size(); ++i) {
            const Body& b = bodies_[i];
            if (b.block && b.level == 0 && !b.occupied && b.zmax - b.zmin >= 0.05f) {
                supports.push_back(static_cast<int>(i));
            }
        }
        // The thinnest axis of the object becomes horizontal, one of the others vertical.
        const Eigen::Vector3f e = model.mesh->Bounds().sizes();
        int thin = 0;
        e.minCoeff(&thin);
        const int v1 = (thin + 1) % 3, v2 = (thin + 2) % 3;
        if (supports.empty() || e[thin] > 0.35f * std::min(e[v1], e[v2])) return false;
        for (int tries = 0; tries < 20; ++tries) {
            const int up =
                rng.Uniform() < 0.7 ? (e[v1] < e[v2] ? v1 : v2) : (e[v1] < e[v2] ? v2 : v1);
            const int side = 3 - thin - up;
            Eigen::Matrix3f stand = Eigen::Matrix3f::Zero();  // object axes -> world axes
            stand.col(thin) = -Eigen::Vector3f::UnitX();
            stand.col(up) = Eigen::Vector3f::UnitZ();
            stand.col(side) = Eigen::Vector3f::UnitY();
            if (stand.determinant() < 0.0f) stand.col(side) = -Eigen::Vector3f::UnitY();
            const int s = supports[static_cast<std::size_t>(
                rng.UniformInt(0, static_cast<int>(supports.size()) - 1))];
            const Body& base = bodies_[static_cast<std::size_t>(s)];
            const float a = static_cast<float>(rng.Uniform(0.0, 2.0 * kPi));
            const Eigen::Vector2f u(std::cos(a), std::sin(a));  // from the support to the object
            const float tilt = static_cast<float>(rng.Uniform(10.0, 25.0)) * kPi / 180.0f;
            // Tilt about world y moves the top towards +x; the yaw turns +x towards the support.
            const Eigen::Matrix3f R =
                Eigen::AngleAxisf(a + kPi, Eigen::Vector3f::UnitZ()).toRotationMatrix() *
                Eigen::AngleAxisf(tilt, Eigen::Vector3f::UnitY()).toRotationMatrix() * stand;
            const Candidate c(model, RestingPose(*model.mesh, R, 0.0f));
            const Polygon slice = c.Slice(h_, base.zmin + kLevel, base.zmax - kLevel);
            if (slice.size() < 3) continue;
            float s_lo = 0.0f, s_hi = 1.5f;  // overlapping .. apart
            for (int it = 0; it < 30; ++it) {
                const float t = (s_lo + s_hi) / 2;
                const auto poly = Translated(slice, base.centre + t * u);
                (PolygonSeparation(poly, base.footprint) < kLeanContact ? s_lo : s_hi) = t;
            }
            const Eigen::Vector2f at = base.centre + s_hi * u;
            if (!Inside(Translated(c.pose.footprint, at), lo_, hi_) || !ClearSliced(c, at, s)) {
                continue;
            }
            Add(c, at, h_, ObjectPlacement::kLeaning, s, color);
            bodies_[static_cast<std::size_t>(s)].occupied = true;
            return true;
        }
        return false;
    }

    /// Between body `back` and the camera, 0.5-2.5 cm in front of it and shifted sideways by up to
    /// 45 % of its width, so that it hides part of it.
    bool InFront(const Candidate& c, int back, StreamRng& rng, Color color) {
        const Body& b = bodies_[static_cast<std::size_t>(back)];
        const Eigen::Vector2f across(-camera_.y(), camera_.x());
        float wmin = std::numeric_limits<float>::infinity(), wmax = -wmin;
        for (const auto& q : b.footprint) {
            wmin = std::min(wmin, (q - b.centre).dot(across));
            wmax = std::max(wmax, (q - b.centre).dot(across));
        }
        for (int tries = 0; tries < 30; ++tries) {
            const float gap = static_cast<float>(rng.Uniform(0.005, 0.025));
            const Eigen::Vector2f base =
                b.centre + static_cast<float>(rng.Uniform(-0.45, 0.45)) * (wmax - wmin) * across;
            float s_lo = 0.0f, s_hi = 1.5f;
            for (int it = 0; it < 24; ++it) {
                const float s = (s_lo + s_hi) / 2;
                const auto poly = Translated(c.pose.footprint, base + s * camera_);
                (PolygonSeparation(poly, b.footprint) < gap ? s_lo : s_hi) = s;
            }
            const Eigen::Vector2f at = base + s_hi * camera_;
            const auto fp = Translated(c.pose.footprint, at);
            if (!Inside(fp, lo_, hi_) || !Clear(fp, h_, h_ + c.height, std::min(gap, p_.min_gap))) {
                continue;
            }
            Add(c, at, h_, ObjectPlacement::kStanding, -1, color);
            return true;
        }
        return false;
    }

    const TableSceneParams& p_;
    ObjectSource& source_;
    std::uint64_t seed_;
    Scene scene_;
    std::vector<Body> bodies_;
    float h_ = 0.0f;
    Eigen::Vector2f lo_, hi_;
    int count_ = 0;
    bool stacked_ = false;    ///< an object stands on another
    Eigen::Vector2f camera_;  ///< unit vector from the table centre towards the camera side
};

}  // namespace

const char* TableSceneModeName(TableSceneMode mode) {
    for (const auto& [m, name] : kModeNames) {
        if (m == mode) return name;
    }
    return "default";
}

TableSceneMode ParseTableSceneMode(std::string_view name) {
    for (const auto& [m, n] : kModeNames) {
        if (name == n) return m;
    }
    throw InvalidArgument(fmt::format(
        "scene mode must be default, boxes, stacked, occluded, cylindric, mixed or complex, got "
        "'{}'",
        name));
}

TableSceneParams TableSceneParamsFor(TableSceneMode mode) {
    TableSceneParams p;
    p.mode = mode;
    switch (mode) {
        case TableSceneMode::kBoxes:
            p.min_objects = 3;
            p.max_objects = 6;
            p.clutter = 0.0f;
            break;
        case TableSceneMode::kStacked:
            p.min_objects = 3;
            p.max_objects = 6;
            p.clutter = 0.2f;
            break;
        case TableSceneMode::kOccluded:
            p.min_objects = 4;
            p.max_objects = 6;
            p.clutter = 0.0f;
            break;
        case TableSceneMode::kCylindric:
            p.min_objects = 3;
            p.max_objects = 6;
            p.clutter = 0.2f;
            break;
        case TableSceneMode::kMixed:
            p.min_objects = 5;
            p.max_objects = 7;
            p.clutter = 0.4f;
            break;
        case TableSceneMode::kComplex:
            p.min_objects = 10;
            p.max_objects = 20;
            p.clutter = 0.6f;
            p.table_min_size = {1.2f, 0.7f};
            p.edge_margin = 0.01f;
            break;
        case TableSceneMode::kDefault:
            break;
    }
    return p;
}

ViewpointParams TableViewpointParamsFor(TableSceneMode mode) {
    ViewpointParams v;
    if (mode == TableSceneMode::kOccluded) {
        v.min_height = 1.15f;
        v.max_height = 1.35f;
        v.min_distance = 0.9f;
        v.max_distance = 1.3f;
    }
    if (mode == TableSceneMode::kComplex) {
        v.min_height = 1.3f;
        v.max_height = 1.45f;
        v.min_distance = 0.8f;
        v.max_distance = 1.0f;
    }
    return v;
}

namespace placement_internal {

Scene MakeModeTableScene(const TableSceneParams& params, ObjectSource& source, std::uint64_t seed) {
    return Composer(params, source, seed).Compose();
}

}  // namespace placement_internal
}  // namespace multicue::sim
