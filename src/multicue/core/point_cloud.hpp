#pragma once
/// \file The one point cloud type of multicue: separate vectors per field (structure of arrays).

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "multicue/core/types.hpp"

namespace multicue {

/// A per-point field that multicue has no vector for, kept byte for byte so that files round-trip.
/// `type` and `size` follow PCD: type 'F' (float), 'I' (signed) or 'U' (unsigned), size 1, 2, 4
/// or 8 bytes, `count` elements per point. `data` holds size*count bytes per point, in point order,
/// in the machine's byte order.
struct ExtraField {
    std::string name;
    char type = 'F';
    std::uint8_t size = 4;
    std::uint32_t count = 1;
    std::vector<std::uint8_t> data;

    std::size_t BytesPerPoint() const { return std::size_t{size} * count; }
};

/// A point cloud. `points` is always present; every other field is either empty or has exactly
/// one entry per point. Organized clouds (RGB-D frames) have width*height == size() and height > 1;
/// their invalid points are NaN and keep their place. Unorganized clouds have height == 1.
struct PointCloud {
    std::vector<Eigen::Vector3f> points;
    std::vector<Eigen::Vector3f> normals;  ///< unit normals (NaN where undefined)
    std::vector<Color> colors;
    std::vector<float> curvature;  ///< surface variation lambda0/(lambda0+lambda1+lambda2)
    std::vector<std::uint32_t> labels;
    std::vector<float> intensity;
    std::vector<float> confidence;
    std::vector<ExtraField> extra_fields;

    std::uint32_t width = 0;   ///< columns when organized, else size()
    std::uint32_t height = 1;  ///< rows when organized, else 1

    /// Sensor pose in the cloud's frame (PCD VIEWPOINT): origin and orientation.
    Eigen::Vector3f sensor_origin = Eigen::Vector3f::Zero();
    Eigen::Quaternionf sensor_orientation = Eigen::Quaternionf::Identity();

    PointCloud() = default;
    /// An unorganized cloud of the given points.
    explicit PointCloud(std::vector<Eigen::Vector3f> pts);

    std::size_t size() const { return points.size(); }
    bool empty() const { return points.empty(); }

    bool HasNormals() const { return !normals.empty(); }
    bool HasColors() const { return !colors.empty(); }
    /// Whether the sensor stands away from the origin: the cloud is then in a world frame. A
    /// rotation alone is not a pose (OpenNI grabbers and PCL's sample scans store the optical
    /// frame with the orientation 0 1 0 0, a viewer convention).
    bool HasSensorPosition() const { return sensor_origin.norm() >= 1e-9f; }
    bool HasCurvature() const { return !curvature.empty(); }
    bool HasLabels() const { return !labels.empty(); }
    bool HasIntensity() const { return !intensity.empty(); }
    bool HasConfidence() const { return !confidence.empty(); }
    bool IsOrganized() const { return height > 1 && std::size_t{width} * height == points.size(); }

    /// Point at row v, column u of an organized cloud.
    const Eigen::Vector3f& At(std::uint32_t u, std::uint32_t v) const {
        return points[std::size_t{v} * width + u];
    }

    /// True when all three coordinates are finite.
    bool IsFinite(std::size_t i) const { return points[i].allFinite(); }
    /// Number of points with finite coordinates.
    std::size_t CountFinite() const;
    /// Whether any point has finite coordinates (stops at the first).
    bool HasFinite() const;

    /// Makes the cloud unorganized (width = size(), height = 1).
    void SetUnorganized();
    /// Resizes every present field to n points (new points are zero); leaves the cloud unorganized.
    void Resize(std::size_t n);
    /// Throws DataError if a present field's size differs from size() or width*height is wrong.
    void Validate() const;

    /// Looks up an extra field by name; nullptr if absent.
    const ExtraField* FindExtraField(const std::string& name) const;
};

/// A new cloud with the given points (in the given order) and all their fields.
/// The result is unorganized; the sensor pose is kept. Throws InvalidArgument on an out-of-range
/// index.
PointCloud SelectByIndex(const PointCloud& cloud, const Indices& indices);

/// At most `max` of `indices`, evenly strided (entry k * size / max for k < max), in order; all of
/// them when there are no more than `max`.
Indices EvenSubset(const Indices& indices, std::size_t max);

/// Axis-aligned bounds of the finite points. Returns false (bounds untouched) if there are none.
bool ComputeBounds(const PointCloud& cloud, Eigen::Vector3f& min, Eigen::Vector3f& max);

}  // namespace multicue
