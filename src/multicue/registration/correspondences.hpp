#pragma once
/// \file Point correspondences for ICP: each source point, moved by the current estimate, is
/// paired with its nearest target point, found in a k-d tree or, on an organized target frame,
/// among the pixels around the point's projection (projective association, Blais and Levine
/// 1995; the fast path for RGB-D frames: no tree to build, a query reads a few pixels). A pair is
/// kept when it passes the distance gate and, where both points have normals, the normal-angle
/// gate (rejects pairs across an edge, e.g. a box side paired with the table).

#include <cstddef>
#include <cstdint>
#include <limits>
#include <optional>
#include <vector>

#include <Eigen/Geometry>

#include "multicue/core/point_cloud.hpp"
#include "multicue/core/types.hpp"
#include "multicue/search/kdtree.hpp"

namespace multicue {

/// How target partners are searched.
enum class CorrespondenceSearch {
    kAuto,        ///< projective when the target is an organized frame in its sensor frame
    kKdTree,      ///< nearest neighbour in a k-d tree of the target
    kProjective,  ///< nearest point in a pixel window around the projection (organized target)
};

/// "auto", "kdtree", "projective"; and back (InvalidArgument naming the choices).
const char* CorrespondenceSearchName(CorrespondenceSearch search);
CorrespondenceSearch ParseCorrespondenceSearch(const std::string& name);

struct CorrespondenceParams {
    float max_distance = 0.05f;  ///< pairs further apart are dropped [m]; > 0
    /// Pairs whose normals differ by more are dropped, (0, 180]; 180 = no normal gate [deg]
    float max_normal_angle_deg = 60.0f;
    CorrespondenceSearch search = CorrespondenceSearch::kAuto;  ///< partner search
    int projective_half_window = 2;  ///< half-size of the projective pixel window, [0, 20] [px]
    /// Throws InvalidArgument naming the first out-of-range field.
    void Validate() const;
};

/// Pinhole intrinsics of an organized frame whose points are in its sensor frame.
struct PinholeModel {
    double fx = 0.0;  ///< [px]
    double fy = 0.0;  ///< [px]
    double cx = 0.0;  ///< [px]
    double cy = 0.0;  ///< [px]
};

/// Recovers fx = fy and the principal point of an organized frame from its points (see
/// EstimateFocalLength); nothing when the cloud is not organized, has its sensor away from the
/// origin (a frame moved into a world frame), looks along -z, or has too few valid pixels.
std::optional<PinholeModel> EstimatePinhole(const PointCloud& organized);

/// One pair: source index, target index and their squared distance [m^2].
struct Correspondence {
    Index source = 0;
    Index target = 0;
    float squared_distance = 0.0f;
};

/// What CorrespondenceSearcher::Find remembers of each subset point's last k-d tree search.
struct NearestCache {
    struct Entry {
        Eigen::Vector3f query = Eigen::Vector3f::Constant(std::numeric_limits<float>::quiet_NaN());
        Index nearest = std::numeric_limits<Index>::max();  ///< none when max
        /// Distance to the nearest point or, without one, a lower bound of it [m]
        float nearest_distance = 0.0f;
        /// Distance to the second-nearest point or a lower bound of it [m]
        float second_distance = 0.0f;
        /// The second-nearest point (second_distance is then its distance); none when max
        Index second = std::numeric_limits<Index>::max();
    };
    std::vector<Entry> entries;  ///< one per subset point; NaN query = not searched yet
};

/// The target side of the search, built once per registration.
class CorrespondenceSearcher {
  public:
    /// `tree` (built from `target`) is used for kKdTree; it may be null when the projective path
    /// is chosen. kAuto picks projective when the target is organized, in its sensor frame and
    /// its pinhole model can be recovered, else the tree. Throws InvalidArgument for bad
    /// parameters, kProjective on a target where it is impossible, or a missing tree.
    CorrespondenceSearcher(const PointCloud& target, const KdTree* tree,
                           const CorrespondenceParams& params);

    /// True when the projective path is used.
    bool projective() const { return pinhole_.has_value(); }
    /// True when a k-d tree is needed for `target` and `params` (no usable projective path).
    static bool NeedsTree(const PointCloud& target, const CorrespondenceParams& params);

    /// Pairs for the source points `subset` moved by T_target_source, in the order of `subset`
    /// (points without a partner are left out); `max_distance` overrides the params' gate when
    /// > 0. Points and normals are taken from `source` (normals optional). The result does not
    /// depend on num_threads.
    ///
    /// `cache`, when given, keeps what each subset point's last k-d tree search found, for the
    /// next call with the same subset (an ICP loop): a point that has moved less than the gap
    /// between its nearest and second-nearest target points keeps its partner without a search,
    /// and the other searches start bounded. The result is the same as without the cache. The
    /// cache is reset when its size is not the subset's; pass one cache per subset.
    void Find(const PointCloud& source, const Indices& subset,
              const Eigen::Isometry3d& T_target_source, float max_distance,
              std::vector<Correspondence>& out, int num_threads,
              NearestCache* cache = nullptr) const;

  private:
    // The nearest target point within `gate` of `p` by the k-d tree, through the point's cache
    // entry.
    bool SearchCached(const Eigen::Vector3f& p, float gate, NearestCache::Entry& e, Index& index,
                      float& squared_distance) const;

    const PointCloud& target_;
    const KdTree* tree_;
    CorrespondenceParams params_;
    std::optional<PinholeModel> pinhole_;
};

}  // namespace multicue
