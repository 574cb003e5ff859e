#include "multicue/reconstruction/fit_guidance.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include <fmt/format.h>

#include "multicue/core/exceptions.hpp"
#include "multicue/core/parallel.hpp"
#include "multicue/features/feature_common.hpp"
#include "multicue/search/kdtree.hpp"

namespace multicue {

float RsdSamplingWeight(float r_min, SampledSurface surface, const RsdSamplingParams& params) {
    if (std::isnan(r_min)) return params.floor_weight;
    const float planar = std::clamp(
        (r_min - (params.planar_radius - params.ramp)) / (2.0f * params.ramp), 0.0f, 1.0f);
    const float preference = surface == SampledSurface::kPlanar ? planar : 1.0f - planar;
    return params.floor_weight + (1.0f - params.floor_weight) * preference;
}

void ValidateFitGuidance(const FitGuidance& g, std::size_t cloud_size) {
    if (!(g.rsd.planar_radius > 0.0f) || !std::isfinite(g.rsd.planar_radius)) {
        throw InvalidArgument(
            fmt::format("rsd planar_radius must be > 0 and finite, got {}", g.rsd.planar_radius));
    }
    if (!(g.rsd.ramp > 0.0f) || !std::isfinite(g.rsd.ramp)) {
        throw InvalidArgument(fmt::format("rsd ramp must be > 0 and finite, got {}", g.rsd.ramp));
    }
    if (!(g.rsd.floor_weight > 0.0f && g.rsd.floor_weight <= 1.0f)) {
        throw InvalidArgument(
            fmt::format("rsd floor_weight must be in (0, 1], got {}", g.rsd.floor_weight));
    }
    if (!g.rsd_min_radius.empty() && g.rsd_min_radius.size() != cloud_size) {
        throw InvalidArgument(
            fmt::format("rsd_min_radius must have one value per cloud point ({}), got {}",
                        cloud_size, g.rsd_min_radius.size()));
    }
    for (std::size_t i = 0; i < g.rsd_min_radius.size(); ++i) {
        const float r = g.rsd_min_radius[i];
        if (!std::isnan(r) && !(r >= 0.0f && std::isfinite(r))) {
            throw InvalidArgument(fmt::format(
                "rsd_min_radius must be NaN (unknown) or finite and >= 0, got {} at point {}", r,
                i));
        }
    }
    if (!g.shape_prior.empty() && g.shape_prior.size() != cloud_size) {
        throw InvalidArgument(
            fmt::format("shape_prior must have one value per cloud point ({}), got {}", cloud_size,
                        g.shape_prior.size()));
    }
    for (std::size_t i = 0; i < g.shape_prior.size(); ++i) {
        const float p = g.shape_prior[i];
        if (!(p >= 0.0f && p <= 1.0f)) {
            throw InvalidArgument(
                fmt::format("shape_prior must be in [0, 1], got {} at point {}", p, i));
        }
    }
}

void MakeSacWeights(const FitGuidance& g, SampledSurface surface, std::size_t cloud_size,
                    const Indices& indices, std::vector<float>& sample_weights,
                    std::vector<float>& score_weights) {
    sample_weights.clear();
    score_weights.clear();
    const bool rsd = !g.rsd_min_radius.empty();
    const bool prior = !g.shape_prior.empty();
    if (rsd || prior) {
        sample_weights.assign(cloud_size, 0.0f);
        for (Index i : indices) {
            const float w = rsd ? RsdSamplingWeight(g.rsd_min_radius[i], surface, g.rsd) : 1.0f;
            sample_weights[i] = prior ? w * g.shape_prior[i] : w;
        }
    }
    if (prior) {
        score_weights.assign(cloud_size, 0.0f);
        for (Index i : indices) score_weights[i] = g.shape_prior[i];
    }
}

std::vector<float> RsdMinRadii(const PointCloud& cloud, const Indices& indices,
                               const RsdParams& params) {
    std::vector<float> out(cloud.size(), std::numeric_limits<float>::quiet_NaN());
    for (Index i : indices) {
        if (i >= cloud.size()) {
            throw InvalidArgument(
                fmt::format("index {} out of range for a cloud of {} points", i, cloud.size()));
        }
    }
    if (indices.empty()) return out;
    if (cloud.normals.size() != cloud.size()) {
        throw DataError(fmt::format("RSD needs one normal per point, got {} for {}",
                                    cloud.normals.size(), cloud.size()));
    }
    // Validates the parameters (and the normals) once, on an empty neighbourhood.
    RsdOfNeighbourhood(cloud, Eigen::Vector3f::Zero(), Eigen::Vector3f::UnitZ(), {}, params);
    const KdTree tree(cloud, indices);
    ParallelFor(
        indices.size(), params.num_threads,
        [&](std::size_t k) {
            const Index i = indices[k];
            const Eigen::Vector3f& p = cloud.points[i];
            const Eigen::Vector3f& n = cloud.normals[i];
            if (!p.allFinite() || !n.allFinite() || !(n.squaredNorm() > 0.0f)) return;
            thread_local Indices nn;
            thread_local std::vector<float> d2;
            detail::RadiusNeighbours(tree, p, params.radius, nn, d2);
            std::erase_if(nn, [&](Index j) { return !cloud.normals[j].allFinite(); });
            out[i] = RsdOfNeighbourhood(cloud, p, n, nn, params)[0];
        },
        64);
    return out;
}

}  // namespace multicue
