#pragma once
/// \file Objects and their parts (thesis section 4.2.1): every object hypothesis is
/// over-segmented into smooth parts by normal-angle region growing, and split where its parts
/// meet in concave creases (stacked and touching objects; SplitByConvexity).

#include <cstddef>
#include <vector>

#include <Eigen/Core>

#include "multicue/core/params.hpp"
#include "multicue/core/point_cloud.hpp"
#include "multicue/core/types.hpp"
#include "multicue/segmentation/convexity_split.hpp"
#include "multicue/segmentation/region_growing.hpp"

namespace multicue {

/// One object hypothesis and its parts.
struct ObjectSegment {
    Indices indices;             ///< the object's points, ascending
    std::vector<Indices> parts;  ///< its smooth parts (subsets of `indices`)
};

struct PartSegmentationParams {
    /// The parts. The k cap keeps dense RGB-D objects cheap: with thousands of points within
    /// 5 cm, the nearest ones already decide connectivity.
    RegionGrowingParams region_growing{.k = 16};
    /// Splitting hypotheses along concave part borders; off: every hypothesis stays one object.
    /// Its min_object_points is replaced by SegmentParts' argument.
    Switchable<ConvexitySplitParams> convexity{};
    /// On organized frames a point's k nearest neighbours are searched among the hypotheses'
    /// points in this pixel window around it instead of a k-d tree; 0 = always the tree [pixels]
    int organized_half_window = 3;
    int num_threads = 0;  ///< 0 = all cores; hypotheses are segmented in parallel
    /// Throws InvalidArgument naming the first out-of-range field.
    void Validate() const;
    /// Its parameters once each: configuration key (the field's name), field, meaning. A
    /// visitor reads or records them (io::ConfigSection::operator(); ReadPerceiveParams).
    template <typename V>
    void VisitParams(V& v) {
        v.Node("region_growing", region_growing);
        v.Switch("convexity", convexity,
                 "split hypotheses where their parts meet in concave creases");
        v("organized_half_window", organized_half_window,
          "on organized frames, the k nearest neighbours from this pixel window instead of a "
          "k-d tree (0 = always the tree) [pixels]");
    }
};

struct PartSegmentationResult {
    /// The objects, in the order of the hypotheses and, within one, of SplitByConvexity's groups.
    std::vector<ObjectSegment> objects;
    std::size_t split_hypotheses = 0;  ///< hypotheses cut into several objects
    std::size_t dropped_pieces = 0;    ///< pieces under min_object_points left out
};

/// Parts of every hypothesis of `clusters` (indices into `cloud`, which needs normals), grown on
/// one k-d tree over all of them (on organized frames, in pixel windows over them), and the objects
/// after the concave split: pieces with fewer than `min_object_points` points are no objects.
/// `plane` (a, b, c, d, normal up; zero when unknown) gives the heights SplitByConvexity compares.
/// Deterministic for any thread count. Throws InvalidArgument for bad parameters, DataError without
/// normals.
PartSegmentationResult SegmentParts(const PointCloud& cloud, const std::vector<Indices>& clusters,
                                    const Eigen::Vector4f& plane,
                                    const PartSegmentationParams& params,
                                    std::size_t min_object_points);

}  // namespace multicue
