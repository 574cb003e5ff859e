#pragma once
/// \file Normal-angle region growing: over-segmentation of a cloud into slightly curved parts
/// (thesis section 4.2.1, used for part-based recognition in chapters 4 and 5).
///
/// A point joins a part when it is within `radius` of a point of the part and its normal is less
/// than `max_angle_deg` from the normal of the part's *seed* (not of the neighbour that reached
/// it), so a part never bends by more than 2 * max_angle_deg: a cylinder side splits into arcs of
/// at most 80 degrees with the thesis values. Seeds are taken in order of lowest curvature, so
/// flat parts are found first. Parts with fewer than `min_part_size` points are then merged as a
/// whole into the nearest larger part within `radius`; small parts with no larger part nearby are
/// grouped by distance alone, and groups still too small are discarded (or kept, see
/// `discard_small_parts`).
///
/// The result depends only on the input, never on the order of neighbour lists: seeds with equal
/// curvature are taken by ascending index, and a part is exactly the set of free points
/// reachable from its seed through points that pass the angle test.

#include <cstddef>
#include <cstdint>
#include <vector>

#include "multicue/core/point_cloud.hpp"
#include "multicue/core/types.hpp"
#include "multicue/search/kdtree.hpp"
#include "multicue/search/organized.hpp"

namespace multicue {

/// Part id of a point that belongs to no part.
inline constexpr std::int32_t kNoPart = -1;

struct RegionGrowingParams {
    float radius = 0.05f;  ///< neighbourhood radius, thesis delta [m]; must be > 0
    int k = 0;  ///< if > 0, only the k nearest neighbours within radius are used [points]
    float max_angle_deg = 40.0f;      ///< max angle between a point's normal and its part's seed
                                      ///< normal, thesis alpha [deg]; in (0, 180]
    bool ignore_normal_sign = false;  ///< true for unoriented normals: n and -n are the same
    std::size_t min_part_size = 10;   ///< smaller parts are merged into a neighbour [points]
    bool discard_small_parts = true;  ///< drop parts still under min_part_size after merging;
                                      ///< false keeps them as parts
    Indices subset = {};  ///< points to segment (duplicates ignored); empty = all points
    /// Throws InvalidArgument naming the first out-of-range field.
    void Validate() const;
    /// Its parameters once each: configuration key (the field's name), field, meaning. A
    /// visitor reads or records them (io::ConfigSection::operator(); ReadPerceiveParams).
    template <typename V>
    void VisitParams(V& v) {
        v("radius", radius, "neighbourhood radius, delta of section 4.2.1 [m]");
        v("k", k, "if > 0, at most k neighbours within the radius");
        v("max_angle_deg", max_angle_deg, "angle to the part's seed normal, alpha [deg]");
        v("min_part_size", min_part_size, "smaller parts are merged into a neighbour [points]");
        v("discard_small_parts", discard_small_parts, "drop parts still too small after merging");
    }
};

struct RegionGrowingResult {
    /// Point indices of each part, ascending. Parts are ordered by their seed: lowest seed
    /// curvature first, ties by seed index.
    std::vector<Indices> parts;
    /// The seed point of each part (for merged groups of small parts, the first seed among them).
    Indices seeds;
    /// One entry per cloud point: the position of its part in `parts`, or kNoPart (not segmented,
    /// non-finite point, normal or curvature, or in a discarded small part).
    std::vector<std::int32_t> part_ids;
    std::size_t num_points = 0;            ///< points that were segmented
    std::size_t num_grown_parts = 0;       ///< parts grown from seeds, before merging
    std::size_t num_merged_parts = 0;      ///< small parts merged into a larger part
    std::size_t num_discarded_points = 0;  ///< points of small parts that were dropped
};

/// Normal-angle region growing over the points of `params.subset` (all points when empty) with
/// finite coordinates, normal and curvature; the other points get kNoPart. Zero-length normals
/// count as non-finite.
///
/// `tree` must index every point to be segmented; it may index more (for example the whole cloud
/// when segmenting a subset), those extra points are ignored.
///
/// Throws InvalidArgument if radius is not > 0 and finite, k < 0, max_angle_deg is not in
/// (0, 180], a subset index is out of range, or the tree lacks a point to be segmented.
/// Throws DataError if the (non-empty) cloud has no normals or no curvature, or their sizes differ
/// from the number of points. An empty cloud gives an empty result.
RegionGrowingResult RegionGrowing(const PointCloud& cloud, const KdTree& tree,
                                  const RegionGrowingParams& params);

/// The same on an organized frame without a k-d tree: a point's neighbours are the pixels of
/// `search.mask` (all finite pixels when empty) in the square window of `search.half_window`
/// around it that lie within the radius in 3D, and with params.k > 0 the k nearest of them.
/// Where the window holds a point's k nearest points of the mask, they are the neighbours of
/// RegionGrowing with a tree over the mask's points. Throws InvalidArgument as RegionGrowing does,
/// and for an unorganized cloud, half_window < 1, a mask of the wrong size or a point to segment
/// outside the mask.
RegionGrowingResult RegionGrowingOrganized(const PointCloud& organized,
                                           const RegionGrowingParams& params,
                                           const OrganizedSearchParams& search);

/// The neighbourhoods of many points, searched once (in parallel) and read by any number of
/// region growings over subsets of them. Row r holds the neighbours of point `points[r]`, nearest
/// first: entries [r * stride, r * stride + count[r]).
struct NeighbourTable {
    static constexpr std::uint32_t kNoRow = 0xffffffffu;
    std::size_t stride = 0;             ///< entries reserved per row
    std::vector<std::uint32_t> row_of;  ///< per cloud point: its row, or kNoRow
    std::vector<std::uint16_t> count;   ///< per row: its neighbours
    Indices neighbours;                 ///< rows * stride
    std::vector<float> squared_distances;
};

/// The neighbourhoods RegionGrowingOrganized uses (same params.radius, params.k and `search`) of
/// `points` (indices into `organized`), searched on `num_threads` threads (0 = all cores); the
/// same table for any thread count. Throws InvalidArgument as RegionGrowingOrganized does and for
/// an index out of range.
NeighbourTable OrganizedNeighbourTable(const PointCloud& organized, const Indices& points,
                                       const RegionGrowingParams& params,
                                       const OrganizedSearchParams& search, int num_threads = 1);

/// Region growing with the neighbourhoods of `table` (from OrganizedNeighbourTable with the same
/// radius and k): the result of RegionGrowingOrganized. Throws as RegionGrowing does, and
/// InvalidArgument when a point to segment has no row in the table.
RegionGrowingResult RegionGrowing(const PointCloud& cloud, const NeighbourTable& table,
                                  const RegionGrowingParams& params);

}  // namespace multicue
