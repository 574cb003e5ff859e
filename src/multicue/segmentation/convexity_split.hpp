#pragma once
/// \file Splits an object hypothesis where its surface folds inwards: stacked and touching objects
/// meet in concave creases, while the faces of one object meet convexly. Parts (from normal-angle
/// region growing, section 4.2.1) are joined when most of the small surface patches along their
/// common border meet convexly, in the spirit of locally convex connected patches (Stein et al.,
/// 2014); each connected group of parts is one object.
///
/// The inside of a hollow object (the visible inner wall and bottom of a bowl, cup or pot) is
/// concave everywhere, yet it is one object with the outer wall. Two groups across a concave
/// border are therefore joined again when the border is a gradual bend, not a crease (the normals
/// of neighbouring patches turn little), and neither group rises above the other: the inside of a
/// hollow object ends at its rim, while an object stacked on another always rises above it.

#include <cstddef>
#include <vector>

#include <Eigen/Core>

#include "multicue/core/params.hpp"
#include "multicue/core/point_cloud.hpp"
#include "multicue/core/types.hpp"
#include "multicue/segmentation/border_classifier.hpp"
#include "multicue/segmentation/folded_parts.hpp"

namespace multicue {

struct ConvexitySplitParams {
    float patch_size = 0.015f;  ///< edge of the voxel patches whose centroids and normals meet [m]
    float smooth_angle_deg = 12.0f;  ///< patches whose normals differ less always join [deg]
    float min_convex_share = 0.5f;   ///< parts join when this share of border patches is convex
    std::size_t min_border = 2;      ///< patch pairs on a border needed to judge it [pairs]
    std::size_t min_object_points = 150;  ///< smaller groups join their best-connected neighbour
    /// A concave border is a gradual bend (the inside of a hollow object) when the median angle
    /// between the normals of its patch pairs is below this [deg], in [0, 180]; 0 disables.
    float bend_angle_deg = 35.0f;
    float max_top_difference = 0.015f;  ///< groups across a bend join when their highest points
                                        ///< above the support plane differ less than this [m]
    /// With a support plane: decide every border by the learned classifier (whether the two
    /// parts are one object) instead of the convex share and the bends above; folded parts are
    /// cut first. Without a plane the rules decide.
    bool learned = true;
    BorderClassifierParams classifier{};
    Switchable<FoldSplitParams> fold{};  ///< cut parts that fold over two faces (learned only)
    /// Throws InvalidArgument naming the first out-of-range field.
    void Validate() const;
    /// Its parameters once each: configuration key (the field's name), field, meaning. A
    /// visitor reads or records them (io::ConfigSection::operator(); ReadPerceiveParams).
    template <typename V>
    void VisitParams(V& v) {
        v("patch_size", patch_size, "voxel patch edge [m]");
        v("smooth_angle_deg", smooth_angle_deg,
          "patches with normals closer than this always join [deg]");
        v("min_convex_share", min_convex_share,
          "parts join when this share of their border is convex");
        v("min_border", min_border, "patch pairs needed to judge a border");
        v("bend_angle_deg", bend_angle_deg,
          "concave borders with a median patch angle below this are bends [deg]; 0 = off");
        v("max_top_difference", max_top_difference,
          "groups across a bend join when their tops differ less than this [m]");
        v("learned", learned,
          "decide borders by the learned classifier (with a support plane) instead of the convex "
          "share and the bends");
        v.Node("classifier", classifier);
        v.Switch("fold", fold, "cut parts whose normals fold over two faces (learned only)");
    }
};

struct ConvexitySplitResult {
    std::vector<Indices> objects;  ///< the object's points split into groups, largest first
    /// The parts of each of `objects`: the given parts, folded ones cut into their pieces.
    std::vector<std::vector<Indices>> parts;
    std::size_t convex_borders = 0;   ///< part borders judged convex (joined)
    std::size_t concave_borders = 0;  ///< part borders judged concave (cut)
    std::size_t bend_joins = 0;       ///< groups joined again across a gradual concave bend
    std::size_t folded_parts = 0;     ///< parts cut where they fold (learned)
};

/// Splits `object` (indices into `cloud`, which must have normals oriented towards the sensor)
/// along concave borders between its `parts` (each a subset of `object`). Points of the object in
/// no part follow the patch they fall into, or the largest group. With fewer than two parts the
/// object comes back whole. `support_plane` (a, b, c, d, normal up) gives the heights for joining
/// across gradual bends; zero skips that step. Throws DataError without normals, InvalidArgument
/// for bad params.
ConvexitySplitResult SplitByConvexity(
    const PointCloud& cloud, const Indices& object, const std::vector<Indices>& parts,
    const ConvexitySplitParams& params,
    const Eigen::Vector4f& support_plane = Eigen::Vector4f::Zero());

}  // namespace multicue
