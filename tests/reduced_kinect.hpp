#pragma once
// The simulated Kinect at a lower resolution, for tests that need fewer rays.

#include <cstdint>

#include "multicue/sim/sensors.hpp"

namespace multicue::test {

/// The default Kinect with its image shrunk by `factor` (2: 320 x 240), focal lengths and
/// principal point scaled with it (the pixel grid's centre stays the image centre).
inline sim::KinectParams ReducedKinect(std::uint32_t factor) {
    sim::KinectParams p;
    const float s = 1.0f / static_cast<float>(factor);
    p.width /= factor;
    p.height /= factor;
    p.fx *= s;
    p.fy *= s;
    p.cx = (p.cx + 0.5f) * s - 0.5f;
    p.cy = (p.cy + 0.5f) * s - 0.5f;
    return p;
}

}  // namespace multicue::test
