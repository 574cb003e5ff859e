#pragma once
/// \file Free-space check of an alignment: a depth camera sees the nearest surface along each
/// ray, so once two frames are aligned, no surface of one may lie in front of what the other
/// measured along the same ray (the other camera would have seen it instead). A wrong alignment
/// that still fits well locally (a table top matched to itself, objects shifted) puts many
/// points into space the other frame saw as free; a right one only a few, near depth edges and
/// where the sensor dropped returns. Thesis section 5.4 verifies models against free space the
/// same way.

#include <cstddef>

#include <Eigen/Geometry>

#include "multicue/core/point_cloud.hpp"

namespace multicue {

struct FreeSpaceParams {
    /// A point violates free space when it lies in front of the measured depth by more than
    /// this plus three depth-noise sigmas [m]; > 0
    float tolerance = 0.03f;
    float depth_noise = 1.4e-3f;    ///< sigma = depth_noise * depth^2 of the frame [1/m]; >= 0
    std::size_t max_points = 5000;  ///< source points tested (evenly strided) [points]; >= 1
    /// Share of violating points above which an alignment is rejected, (0, 1] [-]
    /// (0.02: chosen on the simulated validation sequences, where right alignments put at most
    /// 1.2 % and wrong ones 2.7-7.9 % of their points into free space)
    double max_violation = 0.02;
    /// Throws InvalidArgument naming the first out-of-range field.
    void Validate() const;
};

struct FreeSpaceCheck {
    bool applicable = false;     ///< the frame is organized with a recoverable pinhole model
    std::size_t checked = 0;     ///< points that projected onto a pixel with a depth
    std::size_t violations = 0;  ///< of those, in front of the measured surface
    double ratio = 0.0;          ///< violations / checked [-]
};

/// The points of `source` moved by T_frame_source into the frame of `frame` (an organized depth
/// frame in its sensor frame, see EstimatePinhole) and tested against its depths. Not
/// applicable (nothing checked) for frames that are not organized pinhole frames. Throws
/// InvalidArgument for bad parameters.
FreeSpaceCheck CheckFreeSpace(const PointCloud& source, const PointCloud& frame,
                              const Eigen::Isometry3d& T_frame_source,
                              const FreeSpaceParams& params);

}  // namespace multicue
