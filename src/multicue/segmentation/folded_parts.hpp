#pragma once
/// \file Parts that fold: normal-angle region growing (section 4.2.1) lets a part grow over any
/// surface whose normals stay within its angle of the seed's, so two faces that meet at a shallow
/// crease can become one part. Within one object that is harmless, but where two objects touch
/// or stand on each other (a box set on another one turned by 20 degrees, a bottle against a box)
/// such a part holds pieces of both, and no grouping of parts can separate them again.
///
/// A part's surface normals show the difference: on a smoothly curved part (a cylinder's side)
/// they spread evenly along an arc, on a folded one they gather around two directions with
/// little in between. SplitFoldedParts cuts a part where its point normals form two such modes.

#include <cstddef>
#include <vector>

#include "multicue/core/point_cloud.hpp"
#include "multicue/core/types.hpp"
#include "multicue/segmentation/part_borders.hpp"

namespace multicue {

struct FoldSplitParams {
    float min_fold_deg = 15.0f;  ///< the two normal modes must be this far apart [deg], (0, 180]
    /// At most this share of the part's normals may lie in the middle third between the two
    /// modes (an even arc has a third there) [-], in [0, 1]
    float max_middle_share = 0.12f;
    float min_side_share = 0.15f;       ///< each mode holds at least this share [-], [0, 0.5]
    std::size_t min_part_points = 200;  ///< smaller parts are not examined [points]
    std::size_t min_piece_points = 50;  ///< smaller pieces join the piece they touch [points]
    /// Throws InvalidArgument naming the first out-of-range field.
    void Validate() const;
    /// Its parameters once each: configuration key (the field's name), field, meaning. A
    /// visitor reads or records them (io::ConfigSection::operator(); ReadPerceiveParams).
    template <typename V>
    void VisitParams(V& v) {
        v("min_fold_deg", min_fold_deg,
          "the two normal modes of a folded part are this far apart [deg]");
        v("max_middle_share", max_middle_share,
          "at most this share of a folded part's normals lies between its two modes");
        v("min_side_share", min_side_share, "each mode holds at least this share of the part");
        v("min_part_points", min_part_points, "smaller parts are not examined [points]");
        v("min_piece_points", min_piece_points,
          "smaller pieces join the piece they touch [points]");
    }
};

/// `parts` (subsets of `object`) with every folded part cut into its connected pieces of one
/// normal mode (the point normals of `cloud`); `borders` is ComputePartBorders(cloud, object,
/// parts, ...), whose patches connect the pieces. Points without a patch or normal go to the
/// largest piece. Unfolded parts come back unchanged, in their order; a cut part's largest piece
/// takes its place and the other pieces follow at the end. Deterministic. Throws
/// InvalidArgument for bad parameters or borders of another object, DataError without normals.
std::vector<Indices> SplitFoldedParts(const PointCloud& cloud, const Indices& object,
                                      const std::vector<Indices>& parts, const PartBorders& borders,
                                      const FoldSplitParams& params);

}  // namespace multicue
