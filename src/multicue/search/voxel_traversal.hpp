#pragma once
/// \file Walking the voxels a line segment crosses (the 3D DDA of Amanatides and Woo), in grid
/// units: cell c covers [c, c + 1) along each axis. Used to find free space by casting the rays
/// from a sensor to its measured points.

#include <algorithm>
#include <cmath>
#include <limits>

#include <Eigen/Core>

namespace multicue {

/// Calls visit(cell) for each cell the segment s -> e enters after the one holding s, in order;
/// stops after the cell holding e or when visit returns false.
template <typename Visit>
void WalkCells(const Eigen::Vector3d& s, const Eigen::Vector3d& e, Visit&& visit) {
    Eigen::Vector3i cell = s.array().floor().cast<int>();
    const Eigen::Vector3i last = e.array().floor().cast<int>();
    const Eigen::Vector3d dir = e - s;
    Eigen::Vector3i step;
    Eigen::Vector3d t_max, t_delta;
    for (int a = 0; a < 3; ++a) {
        if (dir[a] > 0) {
            step[a] = 1;
            t_delta[a] = 1.0 / dir[a];
            t_max[a] = (cell[a] + 1 - s[a]) / dir[a];
        } else if (dir[a] < 0) {
            step[a] = -1;
            t_delta[a] = -1.0 / dir[a];
            t_max[a] = (s[a] - cell[a]) / -dir[a];
        } else {
            step[a] = 0;
            t_delta[a] = t_max[a] = std::numeric_limits<double>::infinity();
        }
    }
    const int max_steps = (last - cell).cwiseAbs().sum();
    for (int k = 0; k < max_steps && cell != last; ++k) {
        int a = 0;
        if (t_max[1] < t_max[a]) a = 1;
        if (t_max[2] < t_max[a]) a = 2;
        if (t_max[a] > 1.0) break;
        cell[a] += step[a];
        t_max[a] += t_delta[a];
        if (!visit(cell)) return;
    }
}

/// Where the segment s -> e lies in the box [lo, hi]: its parameter range [t0, t1] within [0, 1]
/// (s + t (e - s)); false if it misses the box.
inline bool SegmentInBox(const Eigen::Vector3d& s, const Eigen::Vector3d& e,
                         const Eigen::Vector3d& lo, const Eigen::Vector3d& hi, double& t0,
                         double& t1) {
    const Eigen::Vector3d d = e - s;
    t0 = 0.0;
    t1 = 1.0;
    for (int a = 0; a < 3; ++a) {
        if (d[a] == 0.0) {
            if (s[a] < lo[a] || s[a] > hi[a]) return false;
            continue;
        }
        double ta = (lo[a] - s[a]) / d[a];
        double tb = (hi[a] - s[a]) / d[a];
        if (ta > tb) std::swap(ta, tb);
        t0 = std::max(t0, ta);
        t1 = std::min(t1, tb);
        if (t0 > t1) return false;
    }
    return true;
}

/// ClipSegmentToBox with the box's largest coordinates inside it, `inside` = nextafter(dims, 0)
/// per axis, computed once for many segments.
inline bool ClipSegmentToBox(Eigen::Vector3d& s, const Eigen::Vector3d& e,
                             const Eigen::Vector3d& dims, const Eigen::Vector3d& inside) {
    double t0 = 0.0, t1 = 1.0;
    if (!SegmentInBox(s, e, Eigen::Vector3d::Zero(), dims, t0, t1)) return false;
    const Eigen::Vector3d d = e - s;
    s += d * std::min(1.0, t0 + 1e-9);
    for (int a = 0; a < 3; ++a) s[a] = std::clamp(s[a], 0.0, inside[a]);
    return true;
}

/// Moves s along s -> e to where the segment enters the box [0, dims] (a hair inside, so that
/// floor() lands in the box); false if the segment misses the box.
inline bool ClipSegmentToBox(Eigen::Vector3d& s, const Eigen::Vector3d& e,
                             const Eigen::Vector3d& dims) {
    const Eigen::Vector3d inside(std::nextafter(dims[0], 0.0), std::nextafter(dims[1], 0.0),
                                 std::nextafter(dims[2], 0.0));
    return ClipSegmentToBox(s, e, dims, inside);
}

}  // namespace multicue
