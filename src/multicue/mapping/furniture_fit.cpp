#include "multicue/mapping/furniture_fit.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <numbers>

#include <fmt/format.h>

#include "multicue/core/exceptions.hpp"
#include "multicue/search/kdtree.hpp"

namespace multicue {

// One CAD model prepared for fitting.
struct FurnitureFitContext::Cad {
    std::vector<Eigen::Vector3f> points;   ///< sorted by z
    std::vector<Eigen::Vector3f> normals;  ///< same order
    std::vector<float> z;                  ///< heights, ascending
    // Voxels within inlier_distance of a model point.
    Eigen::Vector3f origin = Eigen::Vector3f::Zero();
    float cell = 0.015f;
    Eigen::Vector3i dims = Eigen::Vector3i::Zero();
    std::vector<std::uint8_t> covered;
    std::unique_ptr<KdTree> tree;  ///< over the model's cloud (ICP target)

    bool Covers(const Eigen::Vector3f& p) const {
        const Eigen::Vector3f q = (p - origin) / cell;
        const int x = static_cast<int>(std::floor(q.x())), y = static_cast<int>(std::floor(q.y())),
                  zz = static_cast<int>(std::floor(q.z()));
        if (x < 0 || y < 0 || zz < 0 || x >= dims.x() || y >= dims.y() || zz >= dims.z())
            return false;
        return covered[(static_cast<std::size_t>(x) * dims.y() + y) * dims.z() + zz] != 0;
    }
};

namespace {

constexpr float kPi = std::numbers::pi_v<float>;

double MsSince(std::chrono::steady_clock::time_point t) {
    return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t).count();
}

// Eq. (4.6): iterations after which a better pose is found with probability p_success.
int RequiredIterations(double w, double p_success, int cap) {
    if (w <= 0.0) return cap;
    if (w >= 1.0) return 1;
    const double t = std::log(1.0 - p_success) / std::log(1.0 - w);
    return static_cast<int>(std::min<double>(cap, std::ceil(t)));
}

Eigen::Isometry3f UprightPose(float yaw, const Eigen::Vector2f& t) {
    Eigen::Isometry3f T = Eigen::Isometry3f::Identity();
    T.linear() = Eigen::AngleAxisf(yaw, Eigen::Vector3f::UnitZ()).toRotationMatrix();
    T.translation() = Eigen::Vector3f(t.x(), t.y(), 0.0f);
    return T;
}

// A small deterministic generator (SplitMix64).
struct Rng {
    std::uint64_t s;
    std::uint64_t Next() {
        s += 0x9E3779B97F4A7C15ull;
        std::uint64_t z = s;
        z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
        z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
        return z ^ (z >> 31);
    }
    float Uniform() { return static_cast<float>(Next() >> 40) * 0x1.0p-24f; }
};

}  // namespace

void FurnitureFitParams::Validate() const {
    auto positive = [](float v, const char* name) {
        if (!(v > 0.0f) || !std::isfinite(v)) {
            throw InvalidArgument(fmt::format("furniture fit: {} must be > 0, got {}", name, v));
        }
    };
    positive(inlier_distance, "inlier_distance");
    positive(height_tolerance, "height_tolerance");
    positive(max_offset, "max_offset");
    if (!(success_probability > 0.0 && success_probability < 1.0)) {
        throw InvalidArgument(fmt::format(
            "furniture fit: success_probability must be in (0, 1), got {}", success_probability));
    }
    if (!(checked_share > 0.0f && checked_share <= 1.0f)) {
        throw InvalidArgument(
            fmt::format("furniture fit: checked_share must be in (0, 1], got {}", checked_share));
    }
    if (max_scan_points < 10 || max_candidates < 1 || max_iterations < 1 || max_model_checks < 1 ||
        max_search_checks < 1) {
        throw InvalidArgument(
            "furniture fit: max_scan_points must be >= 10 and max_candidates, max_iterations and "
            "max_model_checks >= 1");
    }
    if (!(min_horizontal_normal >= 0.0f && min_horizontal_normal <= 1.0f)) {
        throw InvalidArgument(
            fmt::format("furniture fit: min_horizontal_normal must be in [0, 1], got {}",
                        min_horizontal_normal));
    }
    if (!(min_coverage >= 0.0f && min_coverage <= 1.0f) ||
        !(max_free_share >= 0.0f && max_free_share <= 1.0f)) {
        throw InvalidArgument("furniture fit: min_coverage and max_free_share must be in [0, 1]");
    }
    if (!(wall_gap >= 0.0f) || !std::isfinite(wall_gap) || !(flip_tolerance >= 0.0f) ||
        !std::isfinite(flip_tolerance)) {
        throw InvalidArgument(
            fmt::format("furniture fit: wall_gap and flip_tolerance must be >= 0, got {} and {}",
                        wall_gap, flip_tolerance));
    }
    if (!(max_scale >= 0.0f && max_scale < 0.5f) || scale_steps < 1 || !(min_scale_gain >= 0.0f) ||
        !std::isfinite(min_scale_gain)) {
        throw InvalidArgument(fmt::format(
            "furniture fit: max_scale must be in [0, 0.5), scale_steps >= 1 and min_scale_gain "
            ">= 0, got {}, {} and {}",
            max_scale, scale_steps, min_scale_gain));
    }
    if (!(occupancy_resolution > 0.0) || !std::isfinite(occupancy_resolution)) {
        throw InvalidArgument(fmt::format("furniture fit: occupancy_resolution must be > 0, got {}",
                                          occupancy_resolution));
    }
    icp.Validate();
}

FurnitureFitContext::FurnitureFitContext(const FurnitureModel& model,
                                         const FurnitureFitParams& params)
    : model_(model), params_(params) {
    params.Validate();
    if (model.cads().empty()) throw InvalidArgument("furniture fit: the model has no CAD models");
    const float eps = params.inlier_distance;
    for (const auto& cad : model.cads()) {
        auto c = std::make_unique<Cad>();
        std::vector<std::size_t> order(cad.cloud.size());
        for (std::size_t i = 0; i < order.size(); ++i) order[i] = i;
        std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
            return cad.cloud.points[a].z() < cad.cloud.points[b].z();
        });
        Eigen::AlignedBox3f box;
        for (std::size_t i : order) {
            c->points.push_back(cad.cloud.points[i]);
            c->normals.push_back(cad.cloud.normals[i]);
            c->z.push_back(cad.cloud.points[i].z());
            box.extend(cad.cloud.points[i]);
        }
        if (c->points.empty()) {
            cads_.push_back(std::move(c));
            continue;
        }
        c->cell = eps / 2;
        c->origin = box.min() - Eigen::Vector3f::Constant(eps + c->cell);
        c->dims = ((box.max() - box.min()) / c->cell).array().ceil().cast<int>() +
                  Eigen::Array3i::Constant(
                      static_cast<int>(std::ceil(2 * (eps + c->cell) / c->cell)) + 1);
        c->covered.assign(static_cast<std::size_t>(c->dims.x()) * c->dims.y() * c->dims.z(), 0);
        const int r = static_cast<int>(std::ceil(eps / c->cell));
        for (const auto& p : c->points) {
            const Eigen::Vector3i q = ((p - c->origin) / c->cell).array().floor().cast<int>();
            for (int dx = -r; dx <= r; ++dx) {
                for (int dy = -r; dy <= r; ++dy) {
                    for (int dz = -r; dz <= r; ++dz) {
                        const Eigen::Vector3i v = q + Eigen::Vector3i(dx, dy, dz);
                        if ((v.array() < 0).any() || (v.array() >= c->dims.array()).any()) continue;
                        const Eigen::Vector3f centre =
                            c->origin + (v.cast<float>().array() + 0.5f).matrix() * c->cell;
                        if ((centre - p).norm() > eps) continue;
                        c->covered[(static_cast<std::size_t>(v.x()) * c->dims.y() + v.y()) *
                                       c->dims.z() +
                                   v.z()] = 1;
                    }
                }
            }
        }
        c->tree = std::make_unique<KdTree>(cad.cloud);
        cads_.push_back(std::move(c));
    }
}

FurnitureFitContext::~FurnitureFitContext() = default;

FurnitureFreeSpace::FurnitureFreeSpace(double resolution) : resolution_(resolution) {
    if (!(resolution > 0.0) || !std::isfinite(resolution)) {
        throw InvalidArgument(
            fmt::format("free space: resolution must be > 0, got {}", resolution));
    }
}

void FurnitureFreeSpace::AddView(const PointCloud& world_points, const Eigen::Vector3f& origin) {
    OccupancyMap map({.resolution = resolution_});
    map.InsertScan(world_points, origin);
    maps_.push_back(std::move(map));
    origins_.push_back(origin);
}

float FurnitureFreeSpace::FreeShare(const std::vector<Eigen::Vector3f>& points) const {
    if (maps_.empty() || points.empty()) return 0.0f;
    std::size_t free = 0;
    for (const auto& p : points) free += IsFree(p) ? 1 : 0;
    return static_cast<float>(free) / static_cast<float>(points.size());
}

bool FurnitureFreeSpace::IsFree(const Eigen::Vector3f& p) const {
    // Free, and so is the next cell along the ray: a point just in front of a surface is not.
    const float step = static_cast<float>(resolution_);
    for (std::size_t v = 0; v < maps_.size(); ++v) {
        const Eigen::Vector3f dir = (p - origins_[v]).normalized();
        if (maps_[v].Query(p) == Occupancy::kFree &&
            maps_[v].Query(p + step * dir) == Occupancy::kFree)
            return true;
    }
    return false;
}

float FurnitureWall::Distance(const Eigen::Vector2f& x) const {
    const Eigen::Vector2f q = x - point;
    const float t = q.dot(Eigen::Vector2f(-normal.y(), normal.x()));
    return t >= lo - 0.3f && t <= hi + 0.3f ? q.dot(normal)
                                            : std::numeric_limits<float>::quiet_NaN();
}

bool BehindWalls(const std::vector<const FurnitureWall*>& walls, const Eigen::Vector2f& x,
                 float margin) {
    for (const auto* w : walls) {
        if (w->Behind(x, margin)) return true;
    }
    return false;
}

namespace {

// Shares of a posed model's points (at most max_checks of them) in the free space of any view
// and behind any wall.
struct Penalty {
    float free = 0.0f;
    float behind = 0.0f;
    float Sum() const { return free + behind; }
};

Penalty ModelPenalty(const PointCloud& cloud, const Eigen::Affine3f& T, std::size_t max_checks,
                     const FurnitureSpace& space, float wall_margin) {
    Penalty out;
    if ((space.free.empty() && space.walls.empty()) || cloud.size() == 0) return out;
    const std::size_t step = std::max<std::size_t>(1, (cloud.size() + max_checks - 1) / max_checks);
    std::vector<Eigen::Vector3f> world;
    for (std::size_t i = 0; i < cloud.size(); i += step) world.push_back(T * cloud.points[i]);
    for (const auto* f : space.free) out.free = std::max(out.free, f->FreeShare(world));
    if (!space.walls.empty()) {
        std::size_t behind = 0;
        for (const auto& p : world)
            behind += BehindWalls(space.walls, p.head<2>(), wall_margin) ? 1 : 0;
        out.behind = static_cast<float>(behind) / static_cast<float>(world.size());
    }
    return out;
}

// The pose (`yaw`, `t_xy`) of model `cad_index` found by the search, refined, stretched, turned
// and tested; `fit` brings the search's counts. `s`, `sn`: the thinned scan points and normals.
FurnitureFit FinishFit(FurnitureFit fit, int cad_index, float yaw, const Eigen::Vector2f& t_xy,
                       const std::vector<Eigen::Vector3f>& s,
                       const std::vector<Eigen::Vector3f>& sn, const Eigen::Vector2f& centre,
                       float max_offset, const FurnitureFitContext& context,
                       const FurnitureSpace& space) {
    const auto t0 = std::chrono::steady_clock::now();
    const FurnitureModel& model = context.model();
    const FurnitureFitParams& p = context.params();
    fit.cad = cad_index;
    fit.yaw = yaw;
    fit.T_world_model = UprightPose(yaw, t_xy);
    const auto& cad = context.cad(static_cast<std::size_t>(fit.cad));
    const auto& target = model.cads()[static_cast<std::size_t>(fit.cad)].cloud;
    // Scan points covered by the model stretched by `scale` and placed by T.
    auto coverage = [&](const Eigen::Isometry3f& T, const Eigen::Vector3f& scale) {
        const Eigen::Isometry3f inv = T.inverse();
        const Eigen::Array3f shrink = scale.array().inverse();
        std::size_t n = 0;
        for (const auto& q : s) n += cad.Covers(((inv * q).array() * shrink).matrix()) ? 1 : 0;
        return n;
    };
    // How well the model stretched by `scale` and placed by T explains the scan: the share of
    // scan points it covers minus the shares of its points in free space and behind walls
    // (`checks` model points checked).
    auto pose_score = [&](const Eigen::Isometry3f& T, const Eigen::Vector3f& scale,
                          std::size_t checks) {
        return static_cast<float>(coverage(T, scale)) / static_cast<float>(s.size()) -
               ModelPenalty(target, T * Eigen::Scaling(scale), checks, space, p.wall_margin).Sum();
    };
    const Eigen::Vector3f one = Eigen::Vector3f::Ones();
    fit.covered = coverage(fit.T_world_model, one);
    if (p.refine) {
        PointCloud src;
        src.points = s;
        src.normals = sn;
        src.width = static_cast<std::uint32_t>(s.size());
        const RegistrationResult r = RegisterIcp(src, target, cad.tree.get(), p.icp,
                                                 fit.T_world_model.inverse().cast<double>());
        if (r.T_target_source.matrix().allFinite()) {
            const Eigen::Isometry3f T = r.T_target_source.inverse().cast<float>();
            const float refined = std::atan2(T.linear()(1, 0), T.linear()(0, 0));
            const Eigen::Isometry3f upright = UprightPose(refined, T.translation().head<2>());
            const std::size_t n = coverage(upright, one);
            if (n >= fit.covered &&
                (upright.translation().head<2>() - centre).norm() <= max_offset) {
                fit.T_world_model = upright;
                fit.yaw = refined;
                fit.covered = n;
                fit.refined = true;
            }
        }
    }
    if (p.max_scale > 0.0f) {
        // Coordinate search over the stretch per axis. The stretch of a horizontal axis keeps
        // one plane across it in place: the model's near face, its far face or the plane through
        // the scan points' centroid, whichever scores best (a face the search aligned stays
        // aligned); the height keeps the floor. T_world_model moves so that the plane stays.
        const Eigen::Isometry3f T0 = fit.T_world_model;
        const Eigen::Isometry3f inv = T0.inverse();
        Eigen::Vector3f centroid = Eigen::Vector3f::Zero();
        for (const auto& q : s) centroid += inv * q;
        centroid /= static_cast<float>(s.size());
        Eigen::AlignedBox3f bounds;
        for (const auto& q : cad.points) bounds.extend(q);
        auto placed = [&](const Eigen::Vector3f& scale, const Eigen::Vector3f& anchor) {
            Eigen::Isometry3f T = T0;
            T.translation() += T0.linear() * (anchor - scale.cwiseProduct(anchor));
            return T;
        };
        auto score = [&](const Eigen::Vector3f& scale, const Eigen::Vector3f& anchor) {
            // Three times the search's model checks: stretches differ by a few per cent.
            return pose_score(placed(scale, anchor), scale, p.max_search_checks * 3);
        };
        Eigen::Vector3f scale = one, anchor = Eigen::Vector3f::Zero();
        float best_score = score(scale, anchor);
        for (int round = 0; round < 2; ++round) {
            for (int axis = 0; axis < 3; ++axis) {
                const std::vector<float> planes =
                    axis == 2 ? std::vector<float>{0.0f}
                              : std::vector<float>{bounds.min()[axis], centroid[axis],
                                                   bounds.max()[axis]};
                Eigen::Vector3f best_scale = scale, best_anchor = anchor;
                for (float plane : planes) {
                    for (int k = -p.scale_steps; k <= p.scale_steps; ++k) {
                        if (k == 0) continue;
                        Eigen::Vector3f trial = scale, at = anchor;
                        trial[axis] = 1.0f + p.max_scale * static_cast<float>(k) /
                                                 static_cast<float>(p.scale_steps);
                        at[axis] = plane;
                        const float sc = score(trial, at);
                        // A stretch must explain the scan clearly better than the model's own
                        // size does (unseen sides and the sampled penalties are noise).
                        if (sc > best_score + p.min_scale_gain) {
                            best_score = sc;
                            best_scale = trial;
                            best_anchor = at;
                        }
                    }
                }
                scale = best_scale;
                anchor = best_anchor;
            }
        }
        if (scale != one) {
            const Eigen::Isometry3f T = placed(scale, anchor);
            if ((T.translation().head<2>() - centre).norm() <= max_offset) {
                fit.T_world_model = T;
                fit.scale = scale;
                fit.covered = coverage(T, scale);
            }
        }
    }
    fit.coverage = static_cast<float>(fit.covered) / static_cast<float>(s.size());
    const Penalty pen =
        ModelPenalty(target, fit.ModelToWorld(), p.max_model_checks, space, p.wall_margin);
    fit.free_share = pen.free;
    fit.behind_share = pen.behind;
    if (p.back_to_wall && !space.walls.empty()) {
        // Front and back: a fit whose front faces a wall right ahead of it is turned by a half
        // turn about its centre when the turned model explains the scan nearly as well. Only
        // the reported orientation changes; FittedModelToWorld() keeps the pose the tests and
        // the verifier judge.
        float depth = 0.0f;
        for (const auto& q : cad.points) depth = std::max(depth, std::abs(q.x()));
        depth *= fit.scale.x();
        const Eigen::Vector2f c = fit.T_world_model.translation().head<2>();
        const Eigen::Vector2f front = fit.T_world_model.linear().col(0).head<2>().normalized();
        bool facing = false;
        for (const auto* w : space.walls) {
            const float dist = w->Distance(c);  // NaN beside the wall: no comparison holds
            facing = facing ||
                     (dist > 0.0f && dist < depth + p.wall_gap && front.dot(w->normal) < -0.7f);
        }
        if (facing) {
            Eigen::Isometry3f turned = fit.T_world_model;
            turned.linear() = turned.linear() * Eigen::Vector3f(-1.0f, -1.0f, 1.0f).asDiagonal();
            if (pose_score(turned, fit.scale, p.max_model_checks) >=
                fit.coverage - pen.Sum() - p.flip_tolerance) {
                fit.T_world_model = turned;
                fit.yaw = std::remainder(fit.yaw + kPi, 2.0f * kPi);
                fit.turned = true;
            }
        }
    }
    if (fit.coverage < p.min_coverage) {
        fit.rejection = "coverage";
    } else if (fit.free_share > p.max_free_share) {
        fit.rejection = "free_space";
    } else if (fit.behind_share > p.max_behind_share) {
        fit.rejection = "behind_wall";
    } else {
        fit.rejection.clear();
        fit.accepted = true;
    }
    fit.ms += MsSince(t0);
    return fit;
}

}  // namespace

std::vector<FurnitureFit> FitFurnitureModels(const PointCloud& points, int cls,
                                             const Eigen::Vector2f& centre,
                                             const FurnitureFitContext& context,
                                             const FurnitureSpace& space, int count) {
    const auto t0 = std::chrono::steady_clock::now();
    const FurnitureModel& model = context.model();
    const FurnitureFitParams& p = context.params();
    if (cls < 0 || cls >= static_cast<int>(model.classes().size())) {
        throw InvalidArgument(fmt::format("furniture fit: unknown class {}", cls));
    }
    if (points.normals.size() != points.size()) {
        throw InvalidArgument("furniture fit: the scan points need normals");
    }
    if (count < 1) {
        throw InvalidArgument(fmt::format("furniture fit: count must be >= 1, got {}", count));
    }
    FurnitureFit fit;
    fit.rejection = "no_fit";
    // The scan points, thinned evenly.
    std::vector<Eigen::Vector3f> s, sn;
    std::vector<std::size_t> usable;
    for (std::size_t i = 0; i < points.size(); ++i) {
        if (points.points[i].allFinite() && points.normals[i].allFinite()) usable.push_back(i);
    }
    const std::size_t stride =
        std::max<std::size_t>(1, (usable.size() + p.max_scan_points - 1) / p.max_scan_points);
    for (std::size_t k = 0; k < usable.size(); k += stride) {
        s.push_back(points.points[usable[k]]);
        sn.push_back(points.normals[usable[k]]);
    }
    fit.scan_points = s.size();
    if (s.size() < 10) {
        fit.ms = MsSince(t0);
        return {fit};
    }
    Rng rng{p.seed ^ (static_cast<std::uint64_t>(cls) << 32) ^ s.size()};
    // The scan points checked per pose: an even share of them.
    std::vector<Eigen::Vector3f> checked;
    const std::size_t check_stride =
        std::max<std::size_t>(1, static_cast<std::size_t>(std::lround(1.0f / p.checked_share)));
    for (std::size_t k = 0; k < s.size(); k += check_stride) checked.push_back(s[k]);
    const float n_checked = static_cast<float>(checked.size());
    const std::size_t slack = checked.size() / 20;  // poses within 5 % of the best coverage
    const float max_offset = p.max_offset * model.classes()[static_cast<std::size_t>(cls)].width;
    const float hmin = p.min_horizontal_normal;
    struct Pose {
        int cad = -1;
        float score = -2.0f;  ///< coverage share minus penalties
        float yaw = 0.0f;
        Eigen::Vector2f t = Eigen::Vector2f::Zero();
    };
    std::vector<Pose> best_of(model.cads().size());  ///< each model's best pose
    std::size_t global_covered = 0;
    for (std::size_t m = 0; m < model.cads().size(); ++m) {
        if (model.cads()[m].cls != cls) continue;
        const auto& cad = context.cad(m);
        const auto& cloud = model.cads()[m].cloud;
        if (cad.points.empty()) continue;
        ++fit.models_tried;
        std::size_t model_covered = 0;
        // Eq. (4.6) with the best coverage of any model so far: later models stop early.
        int required = RequiredIterations(static_cast<double>(global_covered) / n_checked,
                                          p.success_probability, p.max_iterations);
        for (int it = 0; it < required; ++it) {
            ++fit.iterations;
            const std::size_t si = rng.Next() % s.size();
            const Eigen::Vector3f& sp = s[si];
            const auto lo =
                std::lower_bound(cad.z.begin(), cad.z.end(), sp.z() - p.height_tolerance);
            const auto hi =
                std::upper_bound(cad.z.begin(), cad.z.end(), sp.z() + p.height_tolerance);
            const auto n_band = static_cast<std::size_t>(hi - lo);
            if (n_band == 0) continue;
            const std::size_t first = static_cast<std::size_t>(lo - cad.z.begin());
            const std::size_t tries = std::min(
                p.max_candidates,
                std::max<std::size_t>(1, static_cast<std::size_t>(std::ceil(
                                             p.checked_share * static_cast<float>(n_band)))));
            const Eigen::Vector2f sxy = sn[si].head<2>();
            for (std::size_t c = 0; c < tries; ++c) {
                const std::size_t mi = first + rng.Next() % n_band;
                const Eigen::Vector2f mxy = cad.normals[mi].head<2>();
                float yaw;
                if (sxy.norm() >= hmin && mxy.norm() >= hmin) {
                    yaw = std::atan2(sxy.y(), sxy.x()) - std::atan2(mxy.y(), mxy.x());
                } else {
                    yaw = (2.0f * rng.Uniform() - 1.0f) * kPi;  // rotation undetermined
                }
                const Eigen::Rotation2Df R(yaw);
                const Eigen::Vector2f t = sp.head<2>() - R * cad.points[mi].head<2>();
                if ((t - centre).norm() > max_offset) continue;
                // Covered checked points, abandoned once it cannot come near this model's best.
                const Eigen::Rotation2Df Rinv(-yaw);
                const std::size_t bar = model_covered > slack ? model_covered - slack : 0;
                std::size_t covered = 0;
                bool abandoned = false;
                for (std::size_t k = 0; k < checked.size(); ++k) {
                    if (covered + (checked.size() - k) < bar) {
                        abandoned = true;
                        break;
                    }
                    const Eigen::Vector2f q = Rinv * (checked[k].head<2>() - t);
                    covered += cad.Covers(Eigen::Vector3f(q.x(), q.y(), checked[k].z())) ? 1 : 0;
                }
                if (abandoned || covered < bar || covered == 0) continue;
                const float score = static_cast<float>(covered) / n_checked -
                                    ModelPenalty(cloud, UprightPose(yaw, t), p.max_search_checks,
                                                 space, p.wall_margin)
                                        .Sum();
                if (covered > model_covered) {
                    model_covered = covered;
                    global_covered = std::max(global_covered, covered);
                    required =
                        std::min(required,
                                 RequiredIterations(static_cast<double>(global_covered) / n_checked,
                                                    p.success_probability, p.max_iterations));
                }
                if (score > best_of[m].score) best_of[m] = {static_cast<int>(m), score, yaw, t};
            }
        }
    }
    // The models to finish: each model's best pose by score, the best first (ties: the earlier
    // model), as many as `count`.
    std::vector<Pose> chosen;
    for (const Pose& b : best_of) {
        if (b.cad >= 0) chosen.push_back(b);
    }
    if (chosen.empty()) {
        fit.ms = MsSince(t0);
        return {fit};
    }
    std::stable_sort(chosen.begin(), chosen.end(),
                     [](const Pose& a, const Pose& b) { return a.score > b.score; });
    if (chosen.size() > static_cast<std::size_t>(count))
        chosen.resize(static_cast<std::size_t>(count));
    std::vector<FurnitureFit> fits;
    for (const Pose& pose : chosen)
        fits.push_back(
            FinishFit(fit, pose.cad, pose.yaw, pose.t, s, sn, centre, max_offset, context, space));
    fits.front().ms = MsSince(t0);
    return fits;
}

FurnitureFit FitFurniture(const PointCloud& points, int cls, const Eigen::Vector2f& centre,
                          const FurnitureFitContext& context, const FurnitureSpace& space) {
    return FitFurnitureModels(points, cls, centre, context, space, 1).front();
}

}  // namespace multicue
