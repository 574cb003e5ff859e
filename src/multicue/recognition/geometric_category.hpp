#pragma once
/// \file The geometric categories of the thesis (section 5.1.3, Table 5.1) and a rule-based
/// categoriser for one object seen from a single viewpoint, standing on a support plane. It
/// stands in for the learned part-graph classifier until one is trained.
///
/// Evidence, each in [0, 1] (CategorizeObject):
/// - box: share of normals within axis_angle_deg of an axis of the upright box whose faces best
///   match them ("axis_area" of the data README; in simulated scans 0.84-0.91 for boxes,
///   0.36-0.41 for upright cans, 0.07 for a ball),
///   averaged with the share of points in planar region-growing parts when parts are given;
///   without a support plane the box's "up" is the direction shared by the most normals;
/// - cylinder: RANSAC cylinder with normals (FitCylinder), upright (axis within upright_angle_deg
///   of up) or lying (axis within lying_angle_deg of the plane); score = share of side points
///   (within fit_threshold of the side, normal within inlier_normal_angle_deg of radial) + share
///   of points on the visible cap(s), provided the side explains a real share of the points
///   (min_side_ratio .. full_side_ratio), spans most of the object along the axis
///   (min_coverage .. full_coverage: a ball's equator band also fits a cylinder) and the diameter
///   matches the object's size (upright: the footprint's length; lying: the height;
///   size_tolerance);
/// - sphere: RANSAC sphere with normals, hypotheses from pairs of oriented points (FitSphere);
///   share of points on it (same test as the cylinder side), provided the diameter matches the
///   object's largest extent, fading out as axis_area rises from sphere_box_axis_area to
///   sphere_box_axis_area_max (the faces of a large box fit a large sphere within the
///   threshold); from there on no sphere is fitted;
/// - plate: thin (thickness / largest extent), round (hull area / minimum rectangle area across
///   the thin axis: pi/4 for a disc, 1 for a slab) or a dish (box score below dish_box_score ..
///   slab_box_score: a square plate), and no wider than 2 max_radius (the largest round object
///   considered; a flat piece of another surface can look round and thin but is far wider than
///   a dish); seen as a rim: a plate's bottom lies within the table's band, so its points cover
///   little of their hull (footprint_cover), while a solid top of the same outline (a lid, a
///   tool lying flat) scores solid_plate times less. With a support plane only objects
///   whose thin axis is up (lying plates) qualify: across a horizontal axis a single view shows
///   too little of the outline to judge roundness; and not higher than plate_low_height ..
///   plate_high_height above the plane (a flat box under another one shows a round-looking,
///   partly covered outline but stands far higher than a plate);
/// - box vs flat: the rule of the data README on the sorted extents e1 >= e2 >= e3 (flat if
///   e2/e3 >= 2.5; box if e2/e3 < 2.0; in between flat if e1/e3 > 2.8), made soft near the
///   boundaries so that the probabilities show how close the call was;
/// - other: high when no category has strong evidence (below min_evidence).
/// Category scores are raised to `sharpness` and normalised into probabilities; the category is
/// the most probable one (ties go to the lower enum value).

#include <array>
#include <cstddef>
#include <cstdint>
#include <string_view>
#include <vector>

#include <Eigen/Core>

#include "multicue/core/point_cloud.hpp"
#include "multicue/core/types.hpp"

namespace multicue {

/// Geometric categories in the order of the output contract (result.json "categories").
enum class Category : std::uint8_t { kNone = 0, kSphere, kBox, kFlat, kCylinder, kPlate, kOther };

inline constexpr std::size_t kNumCategories = 7;

/// Contract names, indexed by the enum value.
inline constexpr std::array<std::string_view, kNumCategories> kCategoryNames = {
    "none", "sphere", "box", "flat", "cylinder", "plate", "other"};

/// The contract name of a category. Throws InvalidArgument for a value outside the enum.
std::string_view CategoryName(Category category);

/// The category with the given contract name (exact, lower case). Throws InvalidArgument naming
/// the string otherwise.
Category ParseCategory(std::string_view name);

struct CategoryParams {
    std::size_t min_points = 30;    ///< fewer usable points give kNone [points]; >= 1
    std::size_t max_points = 2000;  ///< evidence uses at most this many points, an even stride
                                    ///< through the object [points]; >= min_points
    float axis_angle_deg = 10.0f;   ///< a normal this close to a box axis is box-like, (0, 45]
                                    ///< [deg]
    float planar_part_angle_deg = 10.0f;  ///< a part is planar if its normals deviate from their
                                          ///< mean direction by less than this on average [deg]
    float fit_threshold = 0.006f;  ///< inlier distance of the cylinder and sphere fits [m]; > 0
    float normal_weight = 0.05f;   ///< normal_distance_weight of those fits, [0, 1] [-]
    float inlier_normal_angle_deg = 30.0f;  ///< a point within fit_threshold of a fitted
                                            ///< cylinder's side or sphere counts only with its
                                            ///< normal this close to the surface normal, (0, 90]
                                            ///< [deg]
    float min_radius = 0.01f;               ///< smallest cylinder / sphere radius considered [m]
    float max_radius = 0.25f;               ///< largest cylinder / sphere / plate radius considered
                                            ///< [m]
    float upright_angle_deg = 15.0f;  ///< upright cylinder: axis within this angle of up [deg]
    float lying_angle_deg = 20.0f;    ///< lying cylinder: axis within this angle of the plane
                                      ///< [deg]
    int max_iterations = 500;         ///< sample cap of each RANSAC fit [samples]; >= 1
    float min_side_ratio = 0.1f;      ///< cylinder side inliers below this share score 0 [-]
    float full_side_ratio = 0.3f;     ///< ... and count fully from this share [-]
    float min_coverage = 0.5f;        ///< cylinder side points spanning less than this share of the
                                      ///< object's extent along the axis score 0 [-]
    float full_coverage = 0.8f;       ///< ... and count fully from this share [-]
    float size_tolerance = 1.35f;     ///< a diameter within this factor of the matching extent is
                                      ///< plausible, beyond size_tolerance^2 implausible [-]; > 1
    float flat_ratio = 2.5f;          ///< flat if e2/e3 >= flat_ratio [-]
    float box_ratio = 2.0f;        ///< box if e2/e3 < box_ratio; in between see flat_long_ratio [-]
    float flat_long_ratio = 2.8f;  ///< flat in the band if e1/e3 > flat_long_ratio [-]
    float boundary_softness = 8.0f;     ///< slope of the soft box/flat split per unit log-distance
                                        ///< from the rule's boundary [-]; > 0
    float plate_thin_ratio = 0.2f;      ///< thickness / diameter up to this is fully thin [-]
    float plate_thick_ratio = 0.3f;     ///< ... and from this on not thin at all [-]
    float plate_low_height = 0.035f;    ///< with a support plane: objects up to this high may be
                                        ///< plates (tabletop plates are 1.5-3 cm high) [m]
    float plate_high_height = 0.05f;    ///< ... and from this height on are not [m]
    float sphere_box_axis_area = 0.3f;  ///< a sphere's normals hardly align with box axes (a
                                        ///< ball: 0.07, a bowl: 0.01); the sphere score fades
                                        ///< from this axis_area [-]
    float sphere_box_axis_area_max = 0.6f;  ///< ... to 0 at this one [-]
    float round_fill = 0.86f;     ///< hull / rectangle area up to this is fully round (disc: 0.785)
                                  ///< [-]
    float square_fill = 0.94f;    ///< ... and from this on not round at all (rectangle: 1) [-]
    float dish_box_score = 0.3f;  ///< a plate candidate with a box score up to this counts as
                                  ///< round whatever its outline (a square plate's dish has no
                                  ///< box faces) [-]
    float slab_box_score = 0.5f;  ///< ... and from this box score on its outline decides [-]
    float footprint_cell = 0.01f;  ///< grid cell of the footprint cover [m]; > 0
    float rim_cover = 0.6f;        ///< a plate candidate whose points cover up to this share of its
                                   ///< footprint's hull is seen as a rim: a plate's bottom lies
                                   ///< within the table's band and goes with the table [-]
    float solid_cover = 0.8f;      ///< ... from this share on as a solid top [-]
    float solid_plate = 0.5f;      ///< factor on the plate score of a solid top, [0, 1] [-]
    float min_evidence = 0.45f;    ///< "other" wins when no other score reaches this, (0, 1) [-]
    float sharpness = 2.0f;        ///< exponent applied to the scores before normalising [-]; > 0
    std::uint64_t seed = 1;        ///< RANSAC seed; equal seeds give identical results [-]
    int num_threads = 0;  ///< threads of the RANSAC fits (0 = all cores); never changes the
                          ///< result
    /// Throws InvalidArgument naming the first out-of-range field.
    void Validate() const;
    /// Its parameters once each: configuration key (the field's name), field, meaning. A
    /// visitor reads or records them (io::ConfigSection::operator(); ReadPerceiveParams).
    template <typename V>
    void VisitParams(V& v) {
        v("min_points", min_points, "fewer usable points give category none");
        v("max_points", max_points, "evidence uses at most this many points");
        v("axis_angle_deg", axis_angle_deg, "normal this close to a box axis is box-like [deg]");
        v("planar_part_angle_deg", planar_part_angle_deg, "planar part tolerance [deg]");
        v("fit_threshold", fit_threshold, "cylinder and sphere inlier distance [m]");
        v("normal_weight", normal_weight, "normal distance weight of those fits");
        v("min_radius", min_radius, "smallest cylinder or sphere radius [m]");
        v("max_radius", max_radius, "largest cylinder, sphere or plate radius [m]");
        v("upright_angle_deg", upright_angle_deg, "upright cylinder axis tolerance [deg]");
        v("lying_angle_deg", lying_angle_deg, "lying cylinder axis tolerance [deg]");
        v("max_iterations", max_iterations, "RANSAC sample cap");
        v("min_side_ratio", min_side_ratio, "cylinder side share scoring 0");
        v("full_side_ratio", full_side_ratio, "cylinder side share scoring fully");
        v("size_tolerance", size_tolerance, "diameter vs extent tolerance factor");
        v("flat_ratio", flat_ratio, "flat if e2/e3 >= this");
        v("box_ratio", box_ratio, "box if e2/e3 < this");
        v("flat_long_ratio", flat_long_ratio, "in between: flat if e1/e3 > this");
        v("boundary_softness", boundary_softness, "slope of the soft box/flat split");
        v("plate_thin_ratio", plate_thin_ratio, "thickness/diameter fully thin");
        v("plate_thick_ratio", plate_thick_ratio, "thickness/diameter not thin");
        v("plate_low_height", plate_low_height, "objects up to this high may be plates [m]");
        v("plate_high_height", plate_high_height, "objects from this high are no plates [m]");
        v("sphere_box_axis_area", sphere_box_axis_area, "sphere score fades from this axis_area");
        v("sphere_box_axis_area_max", sphere_box_axis_area_max, "... to 0 at this axis_area");
        v("round_fill", round_fill, "footprint fill up to this is round");
        v("square_fill", square_fill, "footprint fill from this is square");
        v("dish_box_score", dish_box_score, "plate candidates up to this box score are dishes");
        v("slab_box_score", slab_box_score, "from this box score the outline decides");
        v("footprint_cell", footprint_cell, "grid cell of the footprint cover [m]");
        v("rim_cover", rim_cover, "footprint cover up to this is a plate's rim");
        v("solid_cover", solid_cover, "footprint cover from this is a solid top");
        v("solid_plate", solid_plate, "factor on the plate score of a solid top");
        v("min_evidence", min_evidence, "other wins below this score");
        v("sharpness", sharpness, "exponent on scores before normalising");
        v("seed", seed, "RANSAC seed");
    }
};

struct CategoryResult {
    Category category = Category::kNone;  ///< most probable category
    /// Per category (indexed by the enum value), sum 1. Only kNone (probability 1) when the object
    /// has fewer than min_points usable points.
    std::array<float, kNumCategories> probabilities{};
    std::array<float, kNumCategories> scores{};  ///< unnormalised category scores in [0, 1]
    float confidence = 0.0f;                     ///< probability of `category` [-]

    std::size_t points = 0;   ///< object points with finite position and normal [points]
    std::size_t sampled = 0;  ///< of which the evidence was computed from [points]
    bool upright = false;     ///< extents measured in the support-plane frame (else an approximate
                              ///< minimum-volume box)
    Eigen::Vector3f extents = Eigen::Vector3f::Zero();  ///< bounding-box extents sorted
                                                        ///< e1 >= e2 >= e3 [m]
    float height = 0.0f;     ///< highest point above the support plane (0 if unknown) [m]
    float box_score = 0.0f;  ///< box-likeness: axis_area, or its mean with planar_part_ratio [-]
    float axis_area = 0.0f;  ///< share of normals within axis_angle_deg of a box axis [-]
    float planar_part_ratio = -1.0f;     ///< share of points in planar parts; -1 without parts [-]
    float cylinder_inlier_ratio = 0.0f;  ///< share of points on the cylinder's side [-]
    float cylinder_cap_ratio = 0.0f;     ///< share of points on its visible cap(s) [-]
    float cylinder_coverage = 0.0f;      ///< share of the object's extent along the axis that the
                                         ///< side points span [-]
    float cylinder_radius = 0.0f;        ///< radius of the best cylinder, 0 if none [m]
    Eigen::Vector3f cylinder_axis = Eigen::Vector3f::Zero();   ///< its unit axis, 0 if none
    Eigen::Vector3f cylinder_point = Eigen::Vector3f::Zero();  ///< a point on its axis [m]
    bool cylinder_upright = false;     ///< the best cylinder is the upright one
    float sphere_inlier_ratio = 0.0f;  ///< share of points on the best sphere, 0 if none [-]
    float sphere_radius = 0.0f;        ///< its radius, 0 if none (or box-like: not fitted) [m]
    float thickness_ratio = 0.0f;      ///< e3 / e1 [-]
    float footprint_fill = 0.0f;    ///< convex hull area / rectangle area across the thinnest box
                                    ///< axis: 1 rectangle, pi/4 disc [-]
    float footprint_cover = -1.0f;  ///< area of the footprint_cell cells holding points / hull
                                    ///< area across that axis, near 1 for a solid top view;
                                    ///< measured for plate candidates only (thin, low, lying),
                                    ///< else -1 [-]
    float side_face_ratio = 0.0f;   ///< share of normals within axis_angle_deg of a horizontal
                                    ///< axis of the upright box (its vertical faces) [-]
};

/// Categorises one object: the points `object` of `cloud` (which needs one normal per point;
/// their sign is ignored), its region-growing parts (may be empty; indices into `cloud`), and the
/// support plane (a, b, c, d) with the normal pointing up, or the zero vector when unknown (the
/// extents then come from an approximate minimum-volume box, "up" for the box score is the
/// direction shared by the most normals, and cylinders may have any axis). Points with a
/// non-finite position or normal are ignored.
///
/// An object with fewer than min_points usable points (an empty one included) gives kNone with
/// probability 1. Deterministic for a fixed seed, whatever the thread count.
/// Throws InvalidArgument for a parameter out of its domain (named in the message), a non-finite
/// support plane or an index out of range; DataError if the cloud has no normals (unless the
/// object is empty).
CategoryResult CategorizeObject(const PointCloud& cloud, const Indices& object,
                                const std::vector<Indices>& parts,
                                const Eigen::Vector4f& support_plane,
                                const CategoryParams& params = {});

}  // namespace multicue
