#include "multicue/registration/rgb_keypoints.hpp"

#include <cmath>
#include <vector>

#include <fmt/format.h>
#include <opencv2/core.hpp>
#include <opencv2/features2d.hpp>

#include "multicue/core/exceptions.hpp"

namespace multicue {
namespace {

struct FrameFeatures {
    std::vector<cv::KeyPoint> keypoints;
    cv::Mat descriptors;
};

void CheckFrame(const PointCloud& frame, const char* which) {
    if (!frame.IsOrganized()) {
        throw InvalidArgument(fmt::format("RGB keypoints need an organized {} frame", which));
    }
    if (!frame.HasColors()) {
        throw InvalidArgument(fmt::format("RGB keypoints need colours in the {} frame", which));
    }
}

FrameFeatures Detect(const PointCloud& frame, const RgbKeypointParams& params) {
    const int w = static_cast<int>(frame.width);
    const int h = static_cast<int>(frame.height);
    cv::Mat gray(h, w, CV_8UC1);
    cv::Mat mask(h, w, CV_8UC1);
    for (int v = 0; v < h; ++v) {
        for (int u = 0; u < w; ++u) {
            const std::size_t i =
                static_cast<std::size_t>(v) * frame.width + static_cast<std::size_t>(u);
            const Color& c = frame.colors[i];
            // ITU-R BT.601 luma, as OpenCV's RGB2GRAY.
            gray.at<std::uint8_t>(v, u) =
                static_cast<std::uint8_t>(std::lround(0.299 * c.r + 0.587 * c.g + 0.114 * c.b));
            mask.at<std::uint8_t>(v, u) = frame.points[i].allFinite() ? 255 : 0;
        }
    }
    cv::Ptr<cv::Feature2D> detector;
    if (params.detector == KeypointDetector::kOrb) {
        detector = cv::ORB::create(params.max_keypoints);
    } else {
        detector = cv::SIFT::create(params.max_keypoints);
    }
    FrameFeatures f;
    detector->detectAndCompute(gray, mask, f.keypoints, f.descriptors);
    return f;
}

Index PixelIndex(const PointCloud& frame, const cv::KeyPoint& kp) {
    const auto u =
        static_cast<std::uint32_t>(std::clamp<long>(std::lround(kp.pt.x), 0, frame.width - 1));
    const auto v =
        static_cast<std::uint32_t>(std::clamp<long>(std::lround(kp.pt.y), 0, frame.height - 1));
    return static_cast<Index>(std::size_t{v} * frame.width + u);
}

}  // namespace

const char* KeypointDetectorName(KeypointDetector detector) {
    return detector == KeypointDetector::kSift ? "sift" : "orb";
}

KeypointDetector ParseKeypointDetector(const std::string& name) {
    if (name == "orb") return KeypointDetector::kOrb;
    if (name == "sift") return KeypointDetector::kSift;
    throw InvalidArgument(fmt::format("unknown keypoint detector '{}' (choices: orb, sift)", name));
}

void RgbKeypointParams::Validate() const {
    if (max_keypoints < 10) {
        throw InvalidArgument(
            fmt::format("RGB keypoints max_keypoints must be >= 10, got {}", max_keypoints));
    }
    if (!(ratio > 0.0f && ratio <= 1.0f)) {
        throw InvalidArgument(fmt::format("RGB keypoints ratio must be in (0, 1], got {}", ratio));
    }
}

PointMatches MatchRgbKeypoints(const PointCloud& source, const PointCloud& target,
                               const RgbKeypointParams& params) {
    params.Validate();
    CheckFrame(source, "source");
    CheckFrame(target, "target");
    // OpenCV's own threads are used inside detection; the results do not depend on them.
    const FrameFeatures fs = Detect(source, params);
    const FrameFeatures ft = Detect(target, params);
    PointMatches m;
    if (fs.descriptors.empty() || ft.descriptors.empty()) return m;
    const int norm = params.detector == KeypointDetector::kOrb ? cv::NORM_HAMMING : cv::NORM_L2;
    cv::BFMatcher matcher(norm, /*crossCheck=*/false);
    std::vector<std::vector<cv::DMatch>> forward;
    matcher.knnMatch(fs.descriptors, ft.descriptors, forward, 2);
    std::vector<int> back_best;
    if (params.mutual) {
        std::vector<cv::DMatch> back;
        matcher.match(ft.descriptors, fs.descriptors, back);
        back_best.assign(ft.keypoints.size(), -1);
        for (const auto& b : back) back_best[static_cast<std::size_t>(b.queryIdx)] = b.trainIdx;
    }
    for (const auto& pair : forward) {
        if (pair.empty()) continue;
        const cv::DMatch& best = pair[0];
        if (params.ratio < 1.0f && pair.size() > 1 &&
            best.distance > params.ratio * pair[1].distance) {
            continue;
        }
        if (params.mutual && back_best[static_cast<std::size_t>(best.trainIdx)] != best.queryIdx) {
            continue;
        }
        const Index s = PixelIndex(source, fs.keypoints[static_cast<std::size_t>(best.queryIdx)]);
        const Index t = PixelIndex(target, ft.keypoints[static_cast<std::size_t>(best.trainIdx)]);
        if (!source.points[s].allFinite() || !target.points[t].allFinite()) continue;
        m.source.push_back(s);
        m.target.push_back(t);
    }
    return m;
}

}  // namespace multicue
