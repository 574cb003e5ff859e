#pragma once
/// \file Conversions between multicue::PointCloud and open3d::geometry::PointCloud (Open3D 0.16),
/// header only: include it in a program that links Open3D.
///
/// Open3D stores double-precision points, normals and colours (r, g, b in [0, 1]) and has no
/// organized layout, labels or alpha. Both directions copy and keep the point order; NaN points
/// stay in place (Open3D's RemoveNonFinitePoints drops them if needed). Colours become
/// channel / 255 and come back rounded and clamped, with alpha 255.

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>

#include <open3d/geometry/PointCloud.h>

#include "multicue/core/point_cloud.hpp"
#include "multicue/core/types.hpp"

namespace multicue::adapters {

/// A multicue cloud (unorganized) of Open3D's points, normals and colours.
inline PointCloud FromOpen3d(const open3d::geometry::PointCloud& in) {
    const std::size_t n = in.points_.size();
    PointCloud out;
    out.points.resize(n);
    for (std::size_t i = 0; i < n; ++i) out.points[i] = in.points_[i].cast<float>();
    if (in.normals_.size() == n && n > 0) {
        out.normals.resize(n);
        for (std::size_t i = 0; i < n; ++i) out.normals[i] = in.normals_[i].cast<float>();
    }
    if (in.colors_.size() == n && n > 0) {
        const auto channel = [](double v) {
            return static_cast<std::uint8_t>(std::lround(std::clamp(v, 0.0, 1.0) * 255.0));
        };
        out.colors.resize(n);
        for (std::size_t i = 0; i < n; ++i) {
            const auto& c = in.colors_[i];
            out.colors[i] = Color{channel(c.x()), channel(c.y()), channel(c.z()), 255};
        }
    }
    out.SetUnorganized();
    return out;
}

/// An Open3D cloud of `in`'s points, and its normals and colours when present. Throws DataError
/// if a field's size differs from the number of points.
inline open3d::geometry::PointCloud ToOpen3d(const PointCloud& in) {
    in.Validate();
    open3d::geometry::PointCloud out;
    out.points_.reserve(in.size());
    for (const auto& p : in.points) out.points_.push_back(p.cast<double>());
    if (in.HasNormals()) {
        out.normals_.reserve(in.size());
        for (const auto& n : in.normals) out.normals_.push_back(n.cast<double>());
    }
    if (in.HasColors()) {
        out.colors_.reserve(in.size());
        for (const auto& c : in.colors) {
            out.colors_.emplace_back(c.r / 255.0, c.g / 255.0, c.b / 255.0);
        }
    }
    return out;
}

}  // namespace multicue::adapters
