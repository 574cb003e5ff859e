#pragma once
/// \file What a fixture candidate looks like (thesis section 4.1.2). A handle stands out of the
/// door it is mounted on, not necessarily out of the face plane fitted to a whole run of
/// furniture: doors stand proud of their frames, and a thin handle seen from 2.5 m is no more
/// than one depth step of a Kinect. So every point near a face is measured against the face's
/// local background (the median height over a window of cells around it), points standing out
/// of it are clustered into candidates, and each candidate is described by one row of named
/// measurements: its shape, how far and how clearly it stands out, how it differs in appearance
/// from the face around it, and whether the face surrounds it. A classifier trained on simulated
/// kitchens (FixtureFeatureNames) or the rules of FixtureByRules decide what it is.

#include <cstdint>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "multicue/core/point_cloud.hpp"
#include "multicue/mapping/semantic_map.hpp"

namespace multicue::mapping {

/// The points near one face (on it or in front of it) in face coordinates, with a bucket grid
/// for neighbourhood queries.
struct FaceSamples {
    Indices points;                  ///< cloud indices
    std::vector<Eigen::Vector2f> q;  ///< face coordinates (u, v) [m]
    std::vector<float> height;       ///< offset from the face plane, along its normal [m]
    std::vector<float> residual;     ///< height above the local background [m]
    std::vector<float> appearance;   ///< grey level or scaled intensity; NaN when unknown
    /// Colour beside the grey level: two opponent channels, (R - G) / sqrt(2) and
    /// (R + G - 2 B) / sqrt(6), in the grey level's units (orthogonal to grey in RGB); empty
    /// without colours, NaN where a sample has none
    std::vector<Eigen::Vector2f> chroma;
    std::vector<float> sigma;  ///< height noise of the point at its range [m]
    std::vector<float> range;  ///< distance to the sensor [m]
    /// Buckets: samples of cell (iu, iv) are order[start[c] .. start[c + 1]), c = iv * nu + iu.
    Eigen::Vector2f origin = Eigen::Vector2f::Zero();
    float cell = 0.03f;
    int nu = 0, nv = 0;
    std::vector<std::uint32_t> start, order;

    std::size_t size() const { return points.size(); }
    /// Cell index of face coordinates q, clamped into the grid.
    std::uint32_t CellOf(const Eigen::Vector2f& q) const;
    /// Calls f(sample) for every sample in the cells overlapping [lo, hi].
    template <typename F>
    void ForEachIn(const Eigen::Vector2f& lo, const Eigen::Vector2f& hi, F&& f) const {
        if (nu == 0 || nv == 0) return;
        const std::uint32_t c0 = CellOf(lo), c1 = CellOf(hi);
        const auto w = static_cast<std::uint32_t>(nu);
        for (std::uint32_t v = c0 / w; v <= c1 / w; ++v) {
            for (std::uint32_t u = c0 % w; u <= c1 % w; ++u) {
                const std::uint32_t c = v * w + u;
                for (std::uint32_t k = start[c]; k < start[c + 1]; ++k) f(order[k]);
            }
        }
    }
};

/// Fills the bucket grid of `s` (cells of `cell` metres over the samples' extent) and the
/// residuals: each sample's height minus the local background, the median over
/// (2 radius + 1)^2 cells of the cells' median heights. Each further pass (`passes` in all)
/// recomputes the background without the samples that stood out of the last one by more than
/// max(exclude, 2 sigma). Throws InvalidArgument for cell <= 0 or radius < 0.
void ComputeFaceResiduals(FaceSamples& s, float cell, int radius, int passes = 2,
                          float exclude = 0.01f);

/// How far each sample's appearance lies from its local background (computed over the grid that
/// ComputeFaceResiduals filled, with the same window): the distance in grey level and, where
/// the samples have colour, the two chroma channels (a steel handle on a door of its grey level
/// but another hue stands out). NaN where the sample or its background has no appearance; all
/// NaN before ComputeFaceResiduals.
std::vector<float> AppearanceContrast(const FaceSamples& s, int radius);

/// The measurements of one fixture candidate (one feature row; FixtureFeatureNames).
struct FixtureEvidence {
    float length = 0.0f;            ///< footprint extent along its main axis [m]
    float width = 0.0f;             ///< footprint extent across it [m]
    float elongation = 0.0f;        ///< length / width [-]
    float plane_protrusion = 0.0f;  ///< farthest point from the face plane [m]
    float local_protrusion = 0.0f;  ///< 90th percentile height minus the surround's median [m]
    float median_residual = 0.0f;   ///< median height above the local background [m]
    float depth_extent = 0.0f;      ///< extent along the face normal [m]
    float protrusion_snr = 0.0f;    ///< local_protrusion over the height noise at its range [-]
    float range = 0.0f;             ///< mean distance to the sensor [m]
    float points = 0.0f;            ///< [points]
    float density = 0.0f;           ///< points * range^2 / footprint area: sampling-independent [1]
    float line_share = 0.0f;        ///< share of points on the RANSAC line
    float circle_share = 0.0f;      ///< share of points on the RANSAC circle
    float verticality = 0.0f;       ///< |direction . up| [-]
    float sides = 0.0f;             ///< sides (of 4) with face points around the footprint
    float min_side_drop = 0.0f;     ///< 90th percentile height minus the highest side's median [m]
    float attached_share = 0.0f;    ///< share of points next to a plane of another orientation
    float border = 0.0f;            ///< 1 when cut by the image border (organized clouds)
    /// Distance of the median appearance (grey and, with colours, chroma) from the surround's
    /// (0 when unknown) [units]
    float contrast = 0.0f;
    float surround_spread = 0.0f;  ///< median distance of the surround from its median [units]
    float edge_distance = 0.0f;    ///< from the centre to the nearest face edge [m]
    float height = 0.0f;           ///< centre above the floor (0 when no floor) [m]
    float fill = 0.0f;             ///< footprint cells occupied / cells of its box [-]
    float recess_share = 0.0f;     ///< share of the surround lying below the background [-]
};

/// The feature names of FixtureFeatureRow, in order; a fixture classifier must have been
/// trained on exactly these columns.
const std::vector<std::string>& FixtureFeatureNames();
std::vector<float> FixtureFeatureRow(const FixtureEvidence& e);

/// The class names a fixture classifier predicts: "none", "handle", "knob".
const std::vector<std::string>& FixtureClassNames();

}  // namespace multicue::mapping
