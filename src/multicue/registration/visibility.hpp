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
    float depth_noise = 1.4e-3f;  ///< sigma = depth_noise * depth^2 of the frame [1/m]; >= 0
    /// Points further in front than the threshold plus this are not counted: the scene changed
    /// there (a person, a door) rather than the alignment being wrong [m]; 0 = count them all
    float max_gap = 0.1f;
    std::size_t max_points = 5000;  ///< source points tested (evenly strided) [points]; >= 1
    /// Share of violating points above which an alignment is rejected, (0, 1] [-]. Chosen on
    /// the simulated validation sequences and the real capture sequence: right alignments put
    /// 0.1 % (simulated) and 0.9-1.2 % (real Kinect frames) of their points there, alignments
    /// off by 1 degree 4-6 %, wrong ones far more.
    double max_violation = 0.03;
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
