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

// One object's pixels over its bounding rectangle in the image of an organized cloud.
struct PixelMask {
    long x0 = 0, y0 = 0, width = 0, height = 0;
    std::vector<char> set;
    bool At(long x, long y) const { return set[static_cast<std::size_t>(y * width + x)] != 0; }
};

// One low object's cells in the plane, and which of them its cells enclose.
struct FloorGrid {
    std::size_t object = 0;
    Eigen::Vector2f lo = Eigen::Vector2f::Zero();
    int width = 0, height = 0;
    std::vector<char> enclosed;  // per cell, row-major
    PixelMask pixels;            // organized clouds: its pixels
};

// Marks the cells that the occupied ones enclose in all eight grid directions.
void MarkEnclosed(const std::vector<char>& occupied, FloorGrid& g) {
    static constexpr int kDirs[8][2] = {{1, 0}, {-1, 0},  {0, 1},  {0, -1},
                                        {1, 1}, {-1, -1}, {1, -1}, {-1, 1}};
    g.enclosed.assign(occupied.size(), 0);
    for (int y = 0; y < g.height; ++y) {
        for (int x = 0; x < g.width; ++x) {
            bool all = true;
            for (const auto& d : kDirs) {
                bool hit = false;
                for (int cx = x + d[0], cy = y + d[1];
                     cx >= 0 && cy >= 0 && cx < g.width && cy < g.height; cx += d[0], cy += d[1]) {
                    if (occupied[static_cast<std::size_t>(cy) * g.width + cx]) {
                        hit = true;
                        break;
                    }
                }
                if (!hit) {
                    all = false;
                    break;
                }
            }
            g.enclosed[static_cast<std::size_t>(y) * g.width + x] = all ? 1 : 0;
        }
    }
}

PixelMask MaskOf(const Indices& object, std::uint32_t image_width) {
    PixelMask m;
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

// Whether the object's pixels surround pixel i in all eight image directions: the object hides
// whatever lies behind its outline, so a point seen inside it is on it (a table seen under an
// overhang at the object's side has the table beside it in the image).
bool PixelEnclosed(const PixelMask& m, Index i, std::uint32_t image_width) {
    static constexpr int kDirs[8][2] = {{1, 0}, {-1, 0},  {0, 1},  {0, -1},
                                        {1, 1}, {-1, -1}, {1, -1}, {-1, 1}};
    const long x = static_cast<long>(i) % image_width - m.x0;
    const long y = static_cast<long>(i) / image_width - m.y0;
    if (x < 0 || y < 0 || x >= m.width || y >= m.height) return false;
    for (const auto& d : kDirs) {
        bool hit = false;
        for (long cx = x + d[0], cy = y + d[1]; cx >= 0 && cy >= 0 && cx < m.width && cy < m.height;
             cx += d[0], cy += d[1]) {
            if (m.At(cx, cy)) {
                hit = true;
                break;
            }
        }
        if (!hit) return false;
    }
    return true;
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
    std::vector<char> taken(cloud.size(), 0);
    for (const Indices& o : objects) {
        for (Index i : o) {
            if (i >= cloud.size()) {
                throw InvalidArgument(
                    fmt::format("enclosed floors: index {} out of range for a cloud of {} points",
                                i, cloud.size()));
            }
            taken[i] = 1;
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
        FloorGrid g;
        g.object = k;
        g.lo = lo;
        g.width = static_cast<int>(std::floor((hi.x() - lo.x()) / cell)) + 1;
        g.height = static_cast<int>(std::floor((hi.y() - lo.y()) / cell)) + 1;
        std::vector<char> occupied(static_cast<std::size_t>(g.width) * g.height, 0);
        for (Index i : objects[k]) {
            if (!cloud.points[i].allFinite()) continue;
            const Eigen::Vector2f c = (in_plane(cloud.points[i]) - lo) / cell;
            const int x = std::min(g.width - 1, static_cast<int>(c.x()));
            const int y = std::min(g.height - 1, static_cast<int>(c.y()));
            occupied[static_cast<std::size_t>(y) * g.width + x] = 1;
        }
        MarkEnclosed(occupied, g);
        if (organized) g.pixels = MaskOf(objects[k], cloud.width);
        grids.push_back(std::move(g));
    }
    if (grids.empty()) return floors;

    // The band's free points in an enclosed cell: in an organized cloud only those inside a low
    // object's image rectangle can be enclosed in the image, so only they are looked at.
    Indices candidates;
    if (organized) {
        for (const FloorGrid& g : grids) {
            const PixelMask& m = g.pixels;
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
            if (!(c.x() >= 0.0f && c.y() >= 0.0f && c.x() < static_cast<float>(g.width) &&
                  c.y() < static_cast<float>(g.height))) {
                continue;
            }
            const auto x = static_cast<std::size_t>(c.x()), y = static_cast<std::size_t>(c.y());
            if (g.enclosed[y * static_cast<std::size_t>(g.width) + x] &&
                (!organized || PixelEnclosed(g.pixels, static_cast<Index>(i), cloud.width))) {
                floors[g.object].push_back(static_cast<Index>(i));
                break;
            }
        }
    }
    return floors;
}

}  // namespace multicue
