#include "multicue/sim/sensors.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <memory>
#include <numbers>

#include <fmt/format.h>

#include "multicue/core/exceptions.hpp"
#include "multicue/core/parallel.hpp"
#include "multicue/sim/rng.hpp"

namespace multicue::sim {
namespace {

constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();
constexpr float kDegToRad = static_cast<float>(std::numbers::pi / 180.0);

// Distinct stream salts so the sensors never share random numbers for equal seeds.
constexpr std::uint64_t kKinectSalt = 0x4B494E45ull;
constexpr std::uint64_t kLaserSalt = 0x4C415345ull;
constexpr std::uint64_t kTofSalt = 0x544F4646ull;

/// Ground-truth per point, filled by the sensors and turned into cloud fields at the end.
struct Truth {
    std::vector<std::uint32_t> labels;
    std::vector<std::uint8_t> category;
    std::vector<std::uint16_t> part;

    explicit Truth(std::size_t n) : labels(n, 0), category(n, 0), part(n, 0) {}
    void Set(std::size_t i, const RayCaster& caster, const RayHit& hit) {
        const SceneObject& obj = caster.scene().objects[hit.object];
        labels[i] = obj.label;
        category[i] = static_cast<std::uint8_t>(obj.category);
        part[i] =
            static_cast<std::uint16_t>(std::min<std::uint32_t>(caster.HitPart(hit) + 1, 0xffffu));
    }
    void MoveInto(PointCloud& cloud) {
        cloud.labels = std::move(labels);
        ExtraField cat{"category", 'U', 1, 1, {}};
        cat.data.assign(category.begin(), category.end());
        ExtraField prt{"part", 'U', 2, 1, {}};
        prt.data.resize(part.size() * 2);
        if (!part.empty()) std::memcpy(prt.data.data(), part.data(), prt.data.size());
        cloud.extra_fields.push_back(std::move(cat));
        cloud.extra_fields.push_back(std::move(prt));
    }
};

void CheckPinhole(std::uint32_t w, std::uint32_t h, float fx, float fy, float min_range,
                  float max_range, float max_incidence_deg) {
    if (w == 0 || h == 0) {
        throw InvalidArgument(fmt::format("image size must be positive, got {}x{}", w, h));
    }
    if (!(fx > 0.0f) || !(fy > 0.0f)) {
        throw InvalidArgument(fmt::format("focal lengths must be > 0, got {} {}", fx, fy));
    }
    if (!(min_range >= 0.0f) || !(max_range > min_range)) {
        throw InvalidArgument(fmt::format(
            "range must satisfy 0 <= min_range < max_range, got {} .. {}", min_range, max_range));
    }
    if (!(max_incidence_deg > 0.0f && max_incidence_deg <= 90.0f)) {
        throw InvalidArgument(
            fmt::format("max_incidence_deg must be in (0, 90], got {}", max_incidence_deg));
    }
}

/// First pass of the pinhole sensors: the noise-free hit of every pixel.
struct PixelHit {
    RayHit hit;
    bool valid = false;  ///< passes range, incidence and shadow tests
};

std::uint8_t NoisyChannel(std::uint8_t c, double noise) {
    return static_cast<std::uint8_t>(std::clamp(std::lround(c + noise), 0L, 255L));
}

/// True if pixel (u, v) lies on a depth edge: a 4-neighbour sees another object or a depth
/// differing by more than `jump`. `depth(i)` is +inf for misses.
template <typename Depth>
bool IsEdge(const std::vector<PixelHit>& px, std::uint32_t w, std::uint32_t h, std::uint32_t u,
            std::uint32_t v, float jump, Depth depth) {
    const std::size_t i = std::size_t{v} * w + u;
    const float z = depth(i);
    auto differs = [&](std::size_t j) {
        if (px[j].hit.object != px[i].hit.object) return true;
        return std::isfinite(z) && std::abs(depth(j) - z) > jump;
    };
    return (u > 0 && differs(i - 1)) || (u + 1 < w && differs(i + 1)) ||
           (v > 0 && differs(i - w)) || (v + 1 < h && differs(i + w));
}

/// Throws InvalidArgument for parameters no Kinect could have.
void CheckKinect(const KinectParams& p) {
    CheckPinhole(p.width, p.height, p.fx, p.fy, p.min_range, p.max_range, p.max_incidence_deg);
    if (!(std::abs(p.baseline) > 0.0f) || !(p.disparity_step >= 0.0f) || !(p.axial_noise >= 0.0f) ||
        !(p.lateral_noise_px >= 0.0f) || !(p.color_noise >= 0.0f)) {
        throw InvalidArgument(fmt::format(
            "kinect: baseline must be != 0 and disparity_step, axial_noise, lateral_noise_px, "
            "color_noise >= 0 (got {}, {}, {}, {}, {})",
            p.baseline, p.disparity_step, p.axial_noise, p.lateral_noise_px, p.color_noise));
    }
    if (!(p.shading >= 0.0f && p.shading <= 1.0f)) {
        throw InvalidArgument(fmt::format("kinect: shading must be in [0, 1], got {}", p.shading));
    }
}

/// The camera-frame ray through pixel (u, v), with z = 1 so that its parameter is the depth.
Eigen::Vector3f KinectRay(const KinectParams& p, std::uint32_t u, std::uint32_t v) {
    return Eigen::Vector3f((static_cast<float>(u) - p.cx) / p.fx,
                           (static_cast<float>(v) - p.cy) / p.fy, 1.0f);
}

/// Pass 1 of the Kinect: the noise-free hit of every pixel, one image row per batch of packets,
/// valid within range, below the incidence limit and (projector_shadow) seen by the projector
/// too, the second ray of the structured-light pair.
std::vector<PixelHit> KinectHits(const RayCaster& caster, const Eigen::Isometry3f& T_world_camera,
                                 const KinectParams& p) {
    const std::uint32_t W = p.width, H = p.height;
    const Eigen::Matrix3f R = T_world_camera.linear();
    const Eigen::Vector3f eye = T_world_camera.translation();
    const Eigen::Vector3f projector = T_world_camera * Eigen::Vector3f(p.baseline, 0.0f, 0.0f);
    const float cos_max = std::cos(p.max_incidence_deg * kDegToRad);
    std::vector<PixelHit> px(std::size_t{W} * H);
    ParallelForChunks(
        H, p.num_threads,
        [&](std::size_t v0, std::size_t v1) {
            std::vector<Eigen::Vector3f> dirs(W), to(W), from(W, projector);
            std::vector<RayHit> hits(W);
            std::vector<float> t_far(W);
            std::unique_ptr<bool[]> active(new bool[W]), shadowed(new bool[W]);
            for (std::size_t v = v0; v < v1; ++v) {
                for (std::uint32_t u = 0; u < W; ++u) {
                    dirs[u] = R * KinectRay(p, u, static_cast<std::uint32_t>(v));
                }
                caster.IntersectBatch(eye, dirs.data(), W, 0.0f, p.max_range, hits.data());
                for (std::uint32_t u = 0; u < W; ++u) {
                    const RayHit& h = hits[u];
                    active[u] = h.Valid() && h.t >= p.min_range &&
                                std::abs(h.normal.dot(dirs[u].normalized())) >= cos_max;
                    shadowed[u] = false;
                    if (!active[u] || !p.projector_shadow) continue;
                    // The projector must see the point too (the second ray of the stereo pair).
                    const Eigen::Vector3f d = eye + h.t * dirs[u] - projector;
                    const float dist = d.norm();
                    const float margin = std::max(1e-3f, 1e-3f * dist);
                    to[u] = d / dist;
                    t_far[u] = dist - margin;
                    if (!(t_far[u] > 0.0f)) active[u] = false;
                }
                if (p.projector_shadow) {
                    caster.OccludedBatch(from.data(), to.data(), t_far.data(), active.get(), W,
                                         0.0f, shadowed.get());
                }
                for (std::uint32_t u = 0; u < W; ++u) {
                    PixelHit& out = px[v * W + u];
                    out.hit = hits[u];
                    out.valid = active[u] && !shadowed[u];
                }
            }
        },
        8);
    return px;
}

/// Pass 2 of the Kinect: lateral noise at depth edges, disparity noise and quantisation, colour
/// noise; one random stream per pixel, so the result does not depend on the threads. The pixel
/// body stays in one piece: its draws must keep their order.
void KinectMeasurements(const RayCaster& caster, const std::vector<PixelHit>& px,
                        const KinectParams& p, std::uint64_t seed, PointCloud& cloud,
                        Truth& truth) {
    const std::uint32_t W = p.width, H = p.height;
    const float sigma_d = KinectDisparitySigma(p);
    const float fb = p.fx * std::abs(p.baseline);
    auto depth = [&](std::size_t i) {
        return px[i].hit.Valid() ? px[i].hit.t : std::numeric_limits<float>::infinity();
    };
    ParallelForChunks(
        H, p.num_threads,
        [&](std::size_t v0, std::size_t v1) {
            for (std::size_t vv = v0; vv < v1; ++vv) {
                const auto v = static_cast<std::uint32_t>(vv);
                for (std::uint32_t u = 0; u < W; ++u) {
                    const std::size_t i = std::size_t{v} * W + u;
                    StreamRng rng(seed ^ kKinectSalt, i);
                    std::size_t src = i;
                    if (p.lateral_noise_px > 0.0f && IsEdge(px, W, H, u, v, p.edge_jump, depth)) {
                        const long du = std::lround(rng.FastGaussian() * p.lateral_noise_px);
                        const long dv = std::lround(rng.FastGaussian() * p.lateral_noise_px);
                        const long su = std::clamp<long>(u + du, 0, W - 1);
                        const long sv = std::clamp<long>(v + dv, 0, H - 1);
                        src = static_cast<std::size_t>(sv) * W + static_cast<std::size_t>(su);
                    }
                    const PixelHit& h = px[src];
                    if (!h.valid) continue;
                    const float z = h.hit.t;
                    float z_noisy = z;
                    const double d = fb / z + rng.Gaussian() * sigma_d;
                    const double dq = p.disparity_step > 0.0f
                                          ? std::round(d / p.disparity_step) * p.disparity_step
                                          : d;
                    if (!(dq > 0.0)) continue;
                    z_noisy = static_cast<float>(fb / dq);
                    if (z_noisy < p.min_range || z_noisy > p.max_range) continue;
                    cloud.points[i] = KinectRay(p, u, v) * z_noisy;
                    Color c = caster.HitColor(h.hit);
                    if (p.shading > 0.0f) {
                        const float cos_inc =
                            std::abs(h.hit.normal.dot(KinectRay(p, u, v).normalized()));
                        const float f = 1.0f - p.shading + p.shading * cos_inc;
                        c = Color{static_cast<std::uint8_t>(c.r * f + 0.5f),
                                  static_cast<std::uint8_t>(c.g * f + 0.5f),
                                  static_cast<std::uint8_t>(c.b * f + 0.5f), 255};
                    }
                    cloud.colors[i] =
                        Color{NoisyChannel(c.r, rng.FastGaussian() * p.color_noise),
                              NoisyChannel(c.g, rng.FastGaussian() * p.color_noise),
                              NoisyChannel(c.b, rng.FastGaussian() * p.color_noise), 255};
                    truth.Set(i, caster, h.hit);
                }
            }
        },
        8);
}

}  // namespace

float KinectDisparitySigma(const KinectParams& p) {
    const double target = double{p.axial_noise} * p.fx * std::abs(p.baseline);
    const double quant = double{p.disparity_step} * p.disparity_step / 12.0;
    return static_cast<float>(std::sqrt(std::max(0.0, target * target - quant)));
}

PointCloud ScanKinect(const RayCaster& caster, const Eigen::Isometry3f& T_world_camera,
                      const KinectParams& p, std::uint64_t seed) {
    CheckKinect(p);
    const std::uint32_t W = p.width, H = p.height;
    const std::size_t n = std::size_t{W} * H;
    const std::vector<PixelHit> px = KinectHits(caster, T_world_camera, p);
    PointCloud cloud;
    cloud.points.assign(n, Eigen::Vector3f::Constant(kNaN));
    cloud.colors.assign(n, Color{0, 0, 0, 255});
    cloud.width = W;
    cloud.height = H;
    Truth truth(n);
    KinectMeasurements(caster, px, p, seed, cloud, truth);
    truth.MoveInto(cloud);
    return cloud;
}

PointCloud ScanKinect(const Scene& scene, const Eigen::Isometry3f& T_world_camera,
                      const KinectParams& params, std::uint64_t seed) {
    const RayCaster caster(scene);
    return ScanKinect(caster, T_world_camera, params, seed);
}

PointCloud ScanLaser(const RayCaster& caster, const Eigen::Isometry3f& T_world_head,
                     const LaserParams& p, std::uint64_t seed) {
    if (!(p.fov_deg > 0.0f && p.fov_deg <= 360.0f) || !(p.beam_step_deg > 0.0f) ||
        !(p.tilt_step_deg > 0.0f) || !(p.tilt_max_deg >= p.tilt_min_deg) ||
        !(p.range_noise >= 0.0f) || !(p.intensity_noise >= 0.0f)) {
        throw InvalidArgument(fmt::format(
            "laser: need 0 < fov_deg <= 360, beam_step_deg > 0, tilt_step_deg > 0, tilt_min_deg "
            "<= tilt_max_deg, range_noise >= 0, intensity_noise >= 0 (got {}, {}, {}, {}..{}, {}, "
            "{})",
            p.fov_deg, p.beam_step_deg, p.tilt_step_deg, p.tilt_min_deg, p.tilt_max_deg,
            p.range_noise, p.intensity_noise));
    }
    if (!(p.min_range >= 0.0f) || !(p.max_range > p.min_range) ||
        !(p.max_incidence_deg > 0.0f && p.max_incidence_deg <= 90.0f)) {
        throw InvalidArgument(fmt::format("laser: bad range {}..{} or max_incidence_deg {}",
                                          p.min_range, p.max_range, p.max_incidence_deg));
    }
    const auto W = static_cast<std::uint32_t>(std::floor(p.fov_deg / p.beam_step_deg + 1e-4f)) + 1;
    const auto H = static_cast<std::uint32_t>(
                       std::floor((p.tilt_max_deg - p.tilt_min_deg) / p.tilt_step_deg + 1e-4f)) +
                   1;
    const std::size_t n = std::size_t{W} * H;
    PointCloud cloud;
    cloud.points.assign(n, Eigen::Vector3f::Constant(kNaN));
    cloud.intensity.assign(n, 0.0f);
    cloud.width = W;
    cloud.height = H;
    Truth truth(n);
    const Eigen::Matrix3f R = T_world_head.linear();
    const Eigen::Vector3f origin = T_world_head.translation();
    const float cos_max = std::cos(p.max_incidence_deg * kDegToRad);
    ParallelForChunks(
        H, p.num_threads,
        [&](std::size_t r0, std::size_t r1) {
            for (std::size_t row = r0; row < r1; ++row) {
                const float tilt =
                    (p.tilt_min_deg + static_cast<float>(row) * p.tilt_step_deg) * kDegToRad;
                const float ct = std::cos(tilt), st = std::sin(tilt);
                for (std::uint32_t j = 0; j < W; ++j) {
                    const float phi =
                        (p.fov_deg / 2 - static_cast<float>(j) * p.beam_step_deg) * kDegToRad;
                    // Beam in the scan plane, then the plane pitched down by `tilt` about y.
                    const Eigen::Vector3f d_head(ct * std::cos(phi), std::sin(phi),
                                                 -st * std::cos(phi));
                    const Eigen::Vector3f d = R * d_head;
                    const RayHit hit = caster.Intersect(origin, d, 0.0f, p.max_range);
                    if (!hit.Valid() || hit.t < p.min_range) continue;
                    if (std::abs(hit.normal.dot(d)) < cos_max) continue;
                    const std::size_t i = row * W + j;
                    StreamRng rng(seed ^ kLaserSalt, i);
                    const float r = hit.t + static_cast<float>(rng.Gaussian()) * p.range_noise;
                    if (r < p.min_range || r > p.max_range) continue;
                    cloud.points[i] = d_head * r;
                    const float remission =
                        caster.HitReflectance(hit) * std::abs(hit.normal.dot(d)) / d.norm();
                    cloud.intensity[i] =
                        std::max(0.0f, remission * (1.0f + static_cast<float>(rng.FastGaussian()) *
                                                               p.intensity_noise));
                    truth.Set(i, caster, hit);
                }
            }
        },
        4);
    truth.MoveInto(cloud);
    return cloud;
}

PointCloud ScanTof(const RayCaster& caster, const Eigen::Isometry3f& T_world_camera,
                   const TofParams& p, std::uint64_t seed) {
    CheckPinhole(p.width, p.height, p.fx, p.fy, p.min_range, p.max_range, p.max_incidence_deg);
    if (!(p.noise_ref >= 0.0f) || !(p.ambient >= 0.0f) || !(p.min_amplitude > 0.0f) ||
        !(p.max_noise > 0.0f)) {
        throw InvalidArgument(fmt::format(
            "tof: need noise_ref >= 0, ambient >= 0, min_amplitude > 0, max_noise > 0 (got {}, "
            "{}, {}, {})",
            p.noise_ref, p.ambient, p.min_amplitude, p.max_noise));
    }
    const std::uint32_t W = p.width, H = p.height;
    const std::size_t n = std::size_t{W} * H;
    const Eigen::Matrix3f R = T_world_camera.linear();
    const Eigen::Vector3f eye = T_world_camera.translation();
    const float cos_max = std::cos(p.max_incidence_deg * kDegToRad);
    auto ray_unit = [&](std::uint32_t u, std::uint32_t v) {
        return Eigen::Vector3f((static_cast<float>(u) - p.cx) / p.fx,
                               (static_cast<float>(v) - p.cy) / p.fy, 1.0f)
            .normalized();
    };
    std::vector<PixelHit> px(n);
    ParallelForChunks(
        H, p.num_threads,
        [&](std::size_t v0, std::size_t v1) {
            for (std::size_t v = v0; v < v1; ++v) {
                for (std::uint32_t u = 0; u < W; ++u) {
                    const Eigen::Vector3f d = R * ray_unit(u, static_cast<std::uint32_t>(v));
                    PixelHit& out = px[v * W + u];
                    out.hit = caster.Intersect(eye, d, 0.0f, p.max_range);
                    out.valid = out.hit.Valid() && out.hit.t >= p.min_range &&
                                std::abs(out.hit.normal.dot(d)) >= cos_max;
                }
            }
        },
        8);
    PointCloud cloud;
    cloud.points.assign(n, Eigen::Vector3f::Constant(kNaN));
    cloud.intensity.assign(n, 0.0f);
    cloud.confidence.assign(n, 0.0f);
    cloud.width = W;
    cloud.height = H;
    Truth truth(n);
    auto range = [&](std::size_t i) {
        return px[i].hit.Valid() ? px[i].hit.t : std::numeric_limits<float>::infinity();
    };
    const float norm = std::sqrt(1.0f + p.ambient);  // sigma = noise_ref at amplitude 1
    ParallelForChunks(
        H, p.num_threads,
        [&](std::size_t v0, std::size_t v1) {
            for (std::size_t vv = v0; vv < v1; ++vv) {
                const auto v = static_cast<std::uint32_t>(vv);
                for (std::uint32_t u = 0; u < W; ++u) {
                    const std::size_t i = std::size_t{v} * W + u;
                    const PixelHit& h = px[i];
                    if (!h.valid) continue;
                    StreamRng rng(seed ^ kTofSalt, i);
                    const Eigen::Vector3f d_cam = ray_unit(u, v);
                    float r = h.hit.t;
                    // Mixed pixel: the footprint straddles an edge, the phase averages depths.
                    if (IsEdge(px, W, H, u, v, p.edge_jump, range)) {
                        const int k = rng.UniformInt(0, 3);
                        const long nu = static_cast<long>(u) + (k == 0 ? -1 : k == 1 ? 1 : 0);
                        const long nv = static_cast<long>(v) + (k == 2 ? -1 : k == 3 ? 1 : 0);
                        const float w = static_cast<float>(rng.Uniform());
                        if (nu >= 0 && nu < W && nv >= 0 && nv < H) {
                            const float rn = range(static_cast<std::size_t>(nv) * W +
                                                   static_cast<std::size_t>(nu));
                            if (std::isfinite(rn)) r = w * r + (1.0f - w) * rn;
                        }
                    }
                    const Color c = caster.HitColor(h.hit);
                    const float albedo =
                        0.1f + 0.9f * (0.299f * c.r + 0.587f * c.g + 0.114f * c.b) / 255.0f;
                    const float cos_inc = std::abs(h.hit.normal.dot(R * d_cam));
                    const float amplitude = albedo * cos_inc / (r * r);
                    if (amplitude < p.min_amplitude) continue;
                    const float sigma =
                        p.noise_ref * std::sqrt(amplitude + p.ambient) / (amplitude * norm);
                    if (sigma > p.max_noise) continue;
                    const float r_noisy = r + static_cast<float>(rng.Gaussian()) * sigma;
                    if (r_noisy < p.min_range || r_noisy > p.max_range) continue;
                    cloud.points[i] = d_cam * r_noisy;
                    cloud.intensity[i] = amplitude;
                    cloud.confidence[i] = std::clamp(1.0f - sigma / p.max_noise, 0.0f, 1.0f);
                    truth.Set(i, caster, h.hit);
                }
            }
        },
        8);
    truth.MoveInto(cloud);
    return cloud;
}

}  // namespace multicue::sim
