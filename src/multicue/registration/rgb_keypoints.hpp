#pragma once
/// \file RGB keypoint correspondences of organized RGB-D frames (thesis section 2.2: point
/// correspondences "computed using both 3D and RGB-based features"): ORB or SIFT keypoints
/// (OpenCV) are detected on the colour image where the depth is valid, their descriptors
/// matched (Hamming for ORB, L2 for SIFT; ratio test, optionally mutual), and each match lifted
/// to the 3D points under the two keypoints. AlignMatchesRansac (feature_alignment.hpp) turns the
/// matches into a transform; textured scenes align where geometry alone is ambiguous (a poster
/// on a wall).

#include <string>

#include "multicue/core/point_cloud.hpp"
#include "multicue/registration/feature_alignment.hpp"

namespace multicue {

enum class KeypointDetector {
    kOrb,   ///< FAST corners with rotated BRIEF (Rublee et al. 2011), binary, fast
    kSift,  ///< difference-of-Gaussian blobs with gradient histograms (Lowe 2004)
};

/// "orb" or "sift"; and back (InvalidArgument naming the choices).
const char* KeypointDetectorName(KeypointDetector detector);
KeypointDetector ParseKeypointDetector(const std::string& name);

struct RgbKeypointParams {
    KeypointDetector detector = KeypointDetector::kOrb;
    int max_keypoints = 2000;  ///< per frame [keypoints]; >= 10
    float ratio = 0.8f;        ///< Lowe's ratio test, (0, 1]; 1 = off [-]
    bool mutual = true;        ///< keep only mutual best matches
    /// Throws InvalidArgument naming the first out-of-range field.
    void Validate() const;
};

/// Keypoint matches between two organized frames with colours, as point indices of the frames
/// (only keypoints on finite points). Throws InvalidArgument for bad parameters or a frame that
/// is not organized or has no colours. A frame without texture gives no matches.
PointMatches MatchRgbKeypoints(const PointCloud& source, const PointCloud& target,
                               const RgbKeypointParams& params);

}  // namespace multicue
