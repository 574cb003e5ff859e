#include "multicue/core/point_cloud.hpp"

#include <algorithm>
#include <cstring>
#include <limits>

#include <fmt/format.h>

#include "multicue/core/exceptions.hpp"

namespace multicue {
namespace {

template <typename T>
void CheckFieldSize(const std::vector<T>& field, std::size_t n, const char* name) {
    if (!field.empty() && field.size() != n) {
        throw DataError(fmt::format("point cloud field '{}' has {} entries for {} points", name,
                                    field.size(), n));
    }
}

template <typename T>
void ResizeIfPresent(std::vector<T>& field, std::size_t n) {
    if (!field.empty()) field.resize(n);
}

template <typename T>
std::vector<T> Gather(const std::vector<T>& field, const Indices& indices) {
    std::vector<T> out;
    if (field.empty()) return out;
    out.reserve(indices.size());
    for (Index i : indices) out.push_back(field[i]);
    return out;
}

}  // namespace

PointCloud::PointCloud(std::vector<Eigen::Vector3f> pts)
    : points(std::move(pts)), width(static_cast<std::uint32_t>(points.size())), height(1) {}

std::size_t PointCloud::CountFinite() const {
    return static_cast<std::size_t>(
        std::count_if(points.begin(), points.end(), [](const auto& p) { return p.allFinite(); }));
}

bool PointCloud::HasFinite() const {
    return std::any_of(points.begin(), points.end(), [](const auto& p) { return p.allFinite(); });
}

void PointCloud::SetUnorganized() {
    width = static_cast<std::uint32_t>(points.size());
    height = 1;
}

void PointCloud::Resize(std::size_t n) {
    points.resize(n, Eigen::Vector3f::Zero());
    ResizeIfPresent(normals, n);
    ResizeIfPresent(colors, n);
    ResizeIfPresent(curvature, n);
    ResizeIfPresent(labels, n);
    ResizeIfPresent(intensity, n);
    ResizeIfPresent(confidence, n);
    for (auto& f : extra_fields) f.data.resize(n * f.BytesPerPoint(), 0);
    SetUnorganized();
}

void PointCloud::Validate() const {
    const std::size_t n = points.size();
    CheckFieldSize(normals, n, "normals");
    CheckFieldSize(colors, n, "colors");
    CheckFieldSize(curvature, n, "curvature");
    CheckFieldSize(labels, n, "labels");
    CheckFieldSize(intensity, n, "intensity");
    CheckFieldSize(confidence, n, "confidence");
    for (const auto& f : extra_fields) {
        if (f.BytesPerPoint() == 0 || f.data.size() != n * f.BytesPerPoint()) {
            throw DataError(fmt::format("extra field '{}' holds {} bytes for {} points of {} bytes",
                                        f.name, f.data.size(), n, f.BytesPerPoint()));
        }
    }
    if (std::size_t{width} * height != n) {
        throw DataError(fmt::format("point cloud is {}x{} but holds {} points", width, height, n));
    }
}

const ExtraField* PointCloud::FindExtraField(const std::string& name) const {
    for (const auto& f : extra_fields) {
        if (f.name == name) return &f;
    }
    return nullptr;
}

Indices EvenSubset(const Indices& indices, std::size_t max) {
    if (indices.size() <= max) return indices;
    Indices out;
    out.reserve(max);
    for (std::size_t k = 0; k < max; ++k) out.push_back(indices[k * indices.size() / max]);
    return out;
}

PointCloud SelectByIndex(const PointCloud& cloud, const Indices& indices) {
    const std::size_t n = cloud.size();
    for (Index i : indices) {
        if (i >= n) {
            throw InvalidArgument(
                fmt::format("index {} is out of range for a cloud of {} points", i, n));
        }
    }
    PointCloud out;
    out.points = Gather(cloud.points, indices);
    out.normals = Gather(cloud.normals, indices);
    out.colors = Gather(cloud.colors, indices);
    out.curvature = Gather(cloud.curvature, indices);
    out.labels = Gather(cloud.labels, indices);
    out.intensity = Gather(cloud.intensity, indices);
    out.confidence = Gather(cloud.confidence, indices);
    for (const auto& f : cloud.extra_fields) {
        ExtraField g{f.name, f.type, f.size, f.count, {}};
        const std::size_t b = f.BytesPerPoint();
        g.data.resize(indices.size() * b);
        for (std::size_t k = 0; k < indices.size(); ++k) {
            std::memcpy(g.data.data() + k * b, f.data.data() + std::size_t{indices[k]} * b, b);
        }
        out.extra_fields.push_back(std::move(g));
    }
    out.SetUnorganized();
    out.sensor_origin = cloud.sensor_origin;
    out.sensor_orientation = cloud.sensor_orientation;
    return out;
}

bool ComputeBounds(const PointCloud& cloud, Eigen::Vector3f& min, Eigen::Vector3f& max) {
    Eigen::Vector3f lo = Eigen::Vector3f::Constant(std::numeric_limits<float>::infinity());
    Eigen::Vector3f hi = -lo;
    bool any = false;
    for (const auto& p : cloud.points) {
        if (!p.allFinite()) continue;
        lo = lo.cwiseMin(p);
        hi = hi.cwiseMax(p);
        any = true;
    }
    if (any) {
        min = lo;
        max = hi;
    }
    return any;
}

}  // namespace multicue
