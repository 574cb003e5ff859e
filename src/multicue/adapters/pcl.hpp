#pragma once
/// \file Conversions between multicue::PointCloud and pcl::PointCloud<PointT> (PCL 1.13), header
/// only: include it in a program that links PCL's common library. Supported point types: those
/// with x y z (PointXYZ, PointXYZRGB, PointXYZRGBA, PointXYZL, PointXYZRGBL, PointNormal, ...);
/// normals alone go through pcl::Normal (ToPclNormals, SetNormalsFromPcl).
///
/// Both directions copy, keep the point order, the organized layout (width x height) and the
/// sensor pose, and leave NaN points in place. A field the target type has and the source lacks
/// keeps the target type's default (colour 0,0,0 opaque, label 0, normal 0 0 0, curvature 0); a
/// field the target type lacks is dropped.

#include <cstddef>
#include <cstdint>
#include <string>

#include <pcl/point_cloud.h>
#include <pcl/point_types.h>

#include "multicue/core/exceptions.hpp"
#include "multicue/core/point_cloud.hpp"
#include "multicue/core/types.hpp"

namespace multicue::adapters {

/// A multicue cloud from a PCL cloud: points, and colours, labels, normals and curvature when
/// PointT has them.
template <typename PointT>
PointCloud FromPcl(const pcl::PointCloud<PointT>& in) {
    static_assert(pcl::traits::has_xyz_v<PointT>, "FromPcl needs a point type with x, y, z");
    const std::size_t n = in.size();
    PointCloud out;
    out.points.resize(n);
    for (std::size_t i = 0; i < n; ++i) out.points[i] = in[i].getVector3fMap();
    if constexpr (pcl::traits::has_color_v<PointT>) {
        out.colors.resize(n);
        for (std::size_t i = 0; i < n; ++i) {
            out.colors[i] = Color{in[i].r, in[i].g, in[i].b, in[i].a};
        }
    }
    if constexpr (pcl::traits::has_label_v<PointT>) {
        out.labels.resize(n);
        for (std::size_t i = 0; i < n; ++i) out.labels[i] = in[i].label;
    }
    if constexpr (pcl::traits::has_normal_v<PointT>) {
        out.normals.resize(n);
        for (std::size_t i = 0; i < n; ++i) out.normals[i] = in[i].getNormalVector3fMap();
    }
    if constexpr (pcl::traits::has_curvature_v<PointT>) {
        out.curvature.resize(n);
        for (std::size_t i = 0; i < n; ++i) out.curvature[i] = in[i].curvature;
    }
    if (in.height > 1 && std::size_t{in.width} * in.height == n) {
        out.width = in.width;
        out.height = in.height;
    } else {
        out.SetUnorganized();
    }
    out.sensor_origin = in.sensor_origin_.template head<3>();
    out.sensor_orientation = in.sensor_orientation_;
    return out;
}

/// A PCL cloud of `in`: points, and colours, labels, normals and curvature when PointT has them
/// and `in` holds them. is_dense is true when every point is finite. Throws DataError if a
/// field's size differs from the number of points.
template <typename PointT>
pcl::PointCloud<PointT> ToPcl(const PointCloud& in) {
    static_assert(pcl::traits::has_xyz_v<PointT>, "ToPcl needs a point type with x, y, z");
    in.Validate();
    const std::size_t n = in.size();
    pcl::PointCloud<PointT> out;
    out.resize(n);
    bool dense = true;
    for (std::size_t i = 0; i < n; ++i) {
        out[i].getVector3fMap() = in.points[i];
        dense = dense && in.points[i].allFinite();
    }
    if constexpr (pcl::traits::has_color_v<PointT>) {
        for (std::size_t i = 0; i < n && in.HasColors(); ++i) {
            const Color c = in.colors[i];
            out[i].r = c.r;
            out[i].g = c.g;
            out[i].b = c.b;
            out[i].a = c.a;
        }
    }
    if constexpr (pcl::traits::has_label_v<PointT>) {
        for (std::size_t i = 0; i < n && in.HasLabels(); ++i) out[i].label = in.labels[i];
    }
    if constexpr (pcl::traits::has_normal_v<PointT>) {
        for (std::size_t i = 0; i < n && in.HasNormals(); ++i) {
            out[i].getNormalVector3fMap() = in.normals[i];
        }
    }
    if constexpr (pcl::traits::has_curvature_v<PointT>) {
        for (std::size_t i = 0; i < n && in.HasCurvature(); ++i) out[i].curvature = in.curvature[i];
    }
    out.width = in.IsOrganized() ? in.width : static_cast<std::uint32_t>(n);
    out.height = in.IsOrganized() ? in.height : 1;
    out.is_dense = dense;
    out.sensor_origin_ << in.sensor_origin, 0.0f;
    out.sensor_orientation_ = in.sensor_orientation;
    return out;
}

/// The normals and curvature of `in` as pcl::Normal (what PCL's normal estimation returns).
/// Throws DataError if `in` has no normals.
inline pcl::PointCloud<pcl::Normal> ToPclNormals(const PointCloud& in) {
    if (!in.HasNormals()) throw DataError("ToPclNormals: the cloud has no normals");
    in.Validate();
    pcl::PointCloud<pcl::Normal> out;
    out.resize(in.size());
    for (std::size_t i = 0; i < in.size(); ++i) {
        out[i].getNormalVector3fMap() = in.normals[i];
        out[i].curvature = in.HasCurvature() ? in.curvature[i] : 0.0f;
    }
    out.width = in.IsOrganized() ? in.width : static_cast<std::uint32_t>(in.size());
    out.height = in.IsOrganized() ? in.height : 1;
    out.is_dense = false;
    return out;
}

/// Sets the normals and curvature of `cloud` from pcl::Normal. Throws InvalidArgument if the
/// sizes differ.
inline void SetNormalsFromPcl(PointCloud& cloud, const pcl::PointCloud<pcl::Normal>& normals) {
    if (normals.size() != cloud.size()) {
        throw InvalidArgument("SetNormalsFromPcl: " + std::to_string(normals.size()) +
                              " normals for a cloud of " + std::to_string(cloud.size()) +
                              " points");
    }
    cloud.normals.resize(normals.size());
    cloud.curvature.resize(normals.size());
    for (std::size_t i = 0; i < normals.size(); ++i) {
        cloud.normals[i] = normals[i].getNormalVector3fMap();
        cloud.curvature[i] = normals[i].curvature;
    }
}

}  // namespace multicue::adapters
