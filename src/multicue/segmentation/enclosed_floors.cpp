#include "multicue/segmentation/enclosed_floors.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>

#include <fmt/format.h>
#include <Eigen/Geometry>

#include "multicue/core/exceptions.hpp"

namespace multicue {

void EnclosedFloorParams::Validate() const {
    if (!(max_object_height > 0.0f) || !std::isfinite(max_object_height)) {
        throw InvalidArgument(fmt::format("max_object_height must be positive and finite, got {}",
                                          max_object_height));
    }
    if (!(max_object_width > 0.0f) || !std::isfinite(max_object_width)) {
        throw InvalidArgument(
            fmt::format("max_object_width must be positive and finite, got {}", max_object_width));
    }
    if (!(below >= 0.0f) || !std::isfinite(below))
        throw InvalidArgument(fmt::format("below must be >= 0 and finite, got {}", below));
    if (!(cell > 0.0f) || !std::isfinite(cell))
        throw InvalidArgument(fmt::format("cell must be positive and finite, got {}", cell));
}

namespace {

// A row-major bitmap over a rectangle whose first column and row are x0 and y0.
struct Bitmap {
    long x0 = 0, y0 = 0, width = 0, height = 0;
    std::vector<char> set;
    bool At(long x, long y) const { return set[static_cast<std::size_t>(y * width + x)] != 0; }
};

// Whether set entries surround (x, y) (rectangle coordinates) in all eight grid directions before
// the rectangle ends.
bool Surrounded(const Bitmap& b, long x, long y) {
    static constexpr int kDirs[8][2] = {{1, 0}, {-1, 0},  {0, 1},  {0, -1},
                                        {1, 1}, {-1, -1}, {1, -1}, {-1, 1}};
    for (const auto& d : kDirs) {
        bool hit = false;
        for (long cx = x + d[0], cy = y + d[1]; cx >= 0 && cy >= 0 && cx < b.width && cy < b.height;
             cx += d[0], cy += d[1]) {
            if (b.At(cx, cy)) {
                hit = true;
                break;
            }
        }
        if (!hit) return false;
    }
    return true;
}

// One low object's cells in the plane (x0, y0 unused: `lo` is the first cell's corner), which of
// them its cells surround, and in an organized cloud its pixels.
struct FloorGrid {
    std::size_t object = 0;
    Eigen::Vector2f lo = Eigen::Vector2f::Zero();
    Bitmap enclosed;
    Bitmap pixels;
};

// The object's pixels over their bounding rectangle in the image.
Bitmap PixelsOf(const Indices& object, std::uint32_t image_width) {
    Bitmap m;
    if (object.empty()) return m;
    const long w = image_width;
    long x0 = w, y0 = std::numeric_limits<long>::max(), x1 = -1, y1 = -1;
    for (Index i : object) {
        const long x = static_cast<long>(i) % w, y = static_cast<long>(i) / w;
        x0 = std::min(x0, x), x1 = std::max(x1, x), y0 = std::min(y0, y), y1 = std::max(y1, y);
    }
    m.x0 = x0, m.y0 = y0, m.width = x1 - x0 + 1, m.height = y1 - y0 + 1;
    m.set.assign(static_cast<std::size_t>(m.width * m.height), 0);
    for (Index i : object) {
        const long x = static_cast<long>(i) % w - x0, y = static_cast<long>(i) / w - y0;
        m.set[static_cast<std::size_t>(y * m.width + x)] = 1;
    }
    return m;
}

// Whether the object's pixels surround pixel i in the image: the object hides whatever lies behind
// its outline, so a point seen inside it is on it (a table seen under an overhang at the object's
// side has the table beside it in the image).
bool PixelEnclosed(const Bitmap& m, Index i, std::uint32_t image_width) {
    const long x = static_cast<long>(i) % image_width - m.x0;
    const long y = static_cast<long>(i) / image_width - m.y0;
    return x >= 0 && y >= 0 && x < m.width && y < m.height && Surrounded(m, x, y);
}

}  // namespace

std::vector<Indices> EnclosedFloors(const PointCloud& cloud, const Eigen::Vector4f& plane,
                                    const std::vector<Indices>& objects, float min_height,
                                    const EnclosedFloorParams& params) {
    params.Validate();
    if (!plane.allFinite()) throw InvalidArgument("enclosed floors: the plane must be finite");
    if (!std::isfinite(min_height))
        throw InvalidArgument(
            fmt::format("enclosed floors: min_height must be finite, got {}", min_height));
    std::vector<Indices> floors(objects.size());
    for (const Indices& o : objects) {
        for (Index i : o) {
            if (i >= cloud.size()) {
                throw InvalidArgument(
                    fmt::format("enclosed floors: index {} out of range for a cloud of {} points",
                                i, cloud.size()));
            }
        }
    }
    const float norm = plane.head<3>().norm();
    if (!(norm > 0.0f) || objects.empty()) return floors;
    const Eigen::Vector3f up = plane.head<3>() / norm;
    const float offset = plane.w() / norm;
    const Eigen::Vector3f u = up.unitOrthogonal(), v = up.cross(u);
    const float cell = params.cell;
    auto in_plane = [&](const Eigen::Vector3f& p) { return Eigen::Vector2f(u.dot(p), v.dot(p)); };

    const bool organized = cloud.IsOrganized();
    // The low objects' grids over their bounding rectangles in the plane.
    std::vector<FloorGrid> grids;
    for (std::size_t k = 0; k < objects.size(); ++k) {
        Eigen::Vector2f lo = Eigen::Vector2f::Constant(std::numeric_limits<float>::infinity());
        Eigen::Vector2f hi = -lo;
        float top = -std::numeric_limits<float>::infinity();
        for (Index i : objects[k]) {
            const Eigen::Vector3f& p = cloud.points[i];
            if (!p.allFinite()) continue;
            top = std::max(top, up.dot(p) + offset);
            const Eigen::Vector2f q = in_plane(p);
            lo = lo.cwiseMin(q);
            hi = hi.cwiseMax(q);
        }
        if (!(top <= params.max_object_height) || !(hi.x() >= lo.x()) ||
            (hi - lo).maxCoeff() > params.max_object_width) {
            continue;
        }
        Bitmap occupied;
        occupied.width = static_cast<long>(std::floor((hi.x() - lo.x()) / cell)) + 1;
        occupied.height = static_cast<long>(std::floor((hi.y() - lo.y()) / cell)) + 1;
        occupied.set.assign(static_cast<std::size_t>(occupied.width * occupied.height), 0);
        for (Index i : objects[k]) {
            if (!cloud.points[i].allFinite()) continue;
            const Eigen::Vector2f c = (in_plane(cloud.points[i]) - lo) / cell;
            const long x = std::min(occupied.width - 1, static_cast<long>(c.x()));
            const long y = std::min(occupied.height - 1, static_cast<long>(c.y()));
            occupied.set[static_cast<std::size_t>(y * occupied.width + x)] = 1;
        }
        FloorGrid g;
        g.object = k;
        g.lo = lo;
        g.enclosed = occupied;
        for (long y = 0; y < occupied.height; ++y) {
            for (long x = 0; x < occupied.width; ++x) {
                g.enclosed.set[static_cast<std::size_t>(y * occupied.width + x)] =
                    Surrounded(occupied, x, y) ? 1 : 0;
            }
        }
        if (organized) g.pixels = PixelsOf(objects[k], cloud.width);
        grids.push_back(std::move(g));
    }
    if (grids.empty()) return floors;
    std::vector<char> taken(cloud.size(), 0);
    for (const Indices& o : objects) {
        for (Index i : o) taken[i] = 1;
    }

    // The band's free points in an enclosed cell: in an organized cloud only those inside a low
    // object's image rectangle can be enclosed in the image, so only they are looked at.
    Indices candidates;
    if (organized) {
        for (const FloorGrid& g : grids) {
            const Bitmap& m = g.pixels;
            for (long y = m.y0; y < m.y0 + m.height; ++y) {
                for (long x = m.x0; x < m.x0 + m.width; ++x)
                    candidates.push_back(static_cast<Index>(y * cloud.width + x));
            }
        }
        std::sort(candidates.begin(), candidates.end());
        candidates.erase(std::unique(candidates.begin(), candidates.end()), candidates.end());
    }
    const std::size_t n = organized ? candidates.size() : cloud.size();
    for (std::size_t k = 0; k < n; ++k) {
        const std::size_t i = organized ? candidates[k] : k;
        if (taken[i]) continue;
        const Eigen::Vector3f& p = cloud.points[i];
        if (!p.allFinite()) continue;
        const float h = up.dot(p) + offset;
        if (h < -params.below || h >= min_height) continue;
        const Eigen::Vector2f q = in_plane(p);
        for (const FloorGrid& g : grids) {
            const Eigen::Vector2f c = (q - g.lo) / cell;
            if (!(c.x() >= 0.0f && c.y() >= 0.0f && c.x() < static_cast<float>(g.enclosed.width) &&
                  c.y() < static_cast<float>(g.enclosed.height))) {
                continue;
            }
            if (g.enclosed.At(static_cast<long>(c.x()), static_cast<long>(c.y())) &&
                (!organized || PixelEnclosed(g.pixels, static_cast<Index>(i), cloud.width))) {
                floors[g.object].push_back(static_cast<Index>(i));
                break;
            }
        }
    }
    return floors;
}

}  // namespace multicue
