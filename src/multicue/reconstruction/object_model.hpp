#pragma once
/// \file Models of perceived objects (thesis section 5.4): the primitive of an object's category
/// (box, cylinder, or a surface of revolution where that explains more), verified against the
/// frame's free space (section 4.2.4.3), replaced by a triangulated mesh of the object's points
/// where it fails (section 5.4.2.3), outlier surfaces attached, and what a gripper needs to know.
/// Also the record of one perceived object that every stage of perceive fills in, and the
/// parameters of the models stage with its model-based grouping (section 5.4.1,
/// reconstruction/model_grouping.hpp).

#include <array>
#include <cstddef>
#include <optional>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Core>

#include "multicue/core/params.hpp"
#include "multicue/core/point_cloud.hpp"
#include "multicue/core/triangle_mesh.hpp"
#include "multicue/core/types.hpp"
#include "multicue/features/rsd.hpp"
#include "multicue/recognition/category_distribution.hpp"
#include "multicue/recognition/geometric_category.hpp"
#include "multicue/reconstruction/part_count_model.hpp"
#include "multicue/reconstruction/primitive_models.hpp"
#include "multicue/reconstruction/rotational_model.hpp"
#include "multicue/reconstruction/verification.hpp"
#include "multicue/surface/greedy_triangulation.hpp"

namespace multicue {

/// Two objects whose cylinders share their axis (within angle_deg and distance), have radii
/// within radius_ratio of each other and overlap along the axis are one object seen as two
/// surfaces (the inside and the outside of a pot or bowl).
struct ConcentricMergeParams {
    bool enabled = true;
    float angle_deg = 8.0f;      ///< axes parallel within this angle [deg]; >= 0
    float distance = 0.02f;      ///< axis to axis at most [m]; >= 0
    float radius_ratio = 0.25f;  ///< |r1 - r2| / max(r1, r2) at most [-]; >= 0
    /// Throws InvalidArgument naming the first out-of-range field.
    void Validate() const;
    /// Its parameters once each: configuration key (the field's name), field, meaning. A
    /// visitor reads or records them (io::ConfigSection::operator(); ReadPerceiveParams).
    template <typename V>
    void VisitParams(V& v) {
        v("enabled", enabled,
          "merge objects whose cylinders share their axis (inside and outside of a pot)");
        v("angle_deg", angle_deg, "axes parallel within [deg]");
        v("distance", distance, "axis to axis at most [m]");
        v("radius_ratio", radius_ratio, "radii differ by at most this share of the larger one");
    }
};

/// An object with at least min_share of its points inside the solid of a larger object's
/// accepted cylinder or surface of revolution, enlarged by margin, is part of it (the bottom
/// inside a bowl, its outer wall, a mug's handle).
struct ContainedMergeParams {
    bool enabled = true;
    float margin = 0.015f;   ///< the container's solid enlarged by this [m]; >= 0
    float min_share = 0.8f;  ///< share of the object's points inside [-]; (0, 1]
    /// Throws InvalidArgument naming the first out-of-range field.
    void Validate() const;
    /// Its parameters once each: configuration key (the field's name), field, meaning. A
    /// visitor reads or records them (io::ConfigSection::operator(); ReadPerceiveParams).
    template <typename V>
    void VisitParams(V& v) {
        v("enabled", enabled,
          "join objects lying inside a container's cylinder or surface of revolution");
        v("margin", margin, "the container's solid enlarged by this [m]");
        v("min_share", min_share, "share of the object's points inside");
    }
};

/// A box or flat object with two horizontal faces (parts with normals within 10 degrees of up,
/// at least min_face_points each) at heights at least min_step apart, the lower one above the
/// table, is split at the lower face's height when two upright boxes explain a share of the points
/// at least min_gain larger than one box.
struct StackedSplitParams {
    bool enabled = true;
    std::size_t min_face_points = 200;  ///< [points]
    float min_step = 0.02f;             ///< [m]; > 0
    float min_gain = 0.05f;             ///< inlier ratio gain of two boxes over one [-]; >= 0
    /// Throws InvalidArgument naming the first out-of-range field.
    void Validate() const;
    /// Its parameters once each: configuration key (the field's name), field, meaning. A
    /// visitor reads or records them (io::ConfigSection::operator(); ReadPerceiveParams).
    template <typename V>
    void VisitParams(V& v) {
        v("enabled", enabled,
          "split box objects with two horizontal faces at different heights into two boxes");
        v("min_face_points", min_face_points, "points of each horizontal face");
        v("min_step", min_step, "height between the faces at least [m]");
        v("min_gain", min_gain,
          "two boxes must explain this much larger a share of the points than one");
    }
};

/// Touching boxes: a box or flat object that one upright box explains poorly (below
/// ModelParams::min_inlier_ratio) is tried as every split of its max_parts largest parts (of at
/// least min_part_points each) into two groups, each an upright box; the best split is kept when
/// each box explains at least min_inlier_ratio of its group, the two solids overlap by at most
/// max_overlap (of either box's volume), and together they explain at least min_gain more of the
/// object's points than one box. Touching round objects (a can standing in a bowl, round_enabled):
/// a sphere, cylinder or other object that one cylinder explains poorly gets a cylinder for the
/// parts it explains and one for the remaining parts; the two are kept when each explains
/// min_inlier_ratio of its parts, together min_gain more of the points than one, and they are not
/// the inside and outside of one container (ConcentricMergeParams).
struct TouchingSplitParams {
    bool enabled = true;                ///< touching boxes
    bool round_enabled = true;          ///< touching round objects
    std::size_t min_part_points = 100;  ///< [points]
    int max_parts = 8;                  ///< [parts]; 2 to 12
    float max_overlap = 0.15f;          ///< [-]; >= 0
    float min_gain = 0.1f;              ///< [-]; >= 0
    std::size_t max_points = 3000;      ///< points used per box evaluation [points]
    /// Throws InvalidArgument naming the first out-of-range field.
    void Validate() const;
    /// Its parameters once each: configuration key (the field's name), field, meaning. A
    /// visitor reads or records them (io::ConfigSection::operator(); ReadPerceiveParams).
    template <typename V>
    void VisitParams(V& v) {
        v("enabled", enabled,
          "split box objects that one box explains poorly into two touching boxes");
        v("min_part_points", min_part_points, "parts taking part in the splits");
        v("max_parts", max_parts, "largest parts tried (2 to 12)");
        v("max_overlap", max_overlap, "the two solid boxes overlap by at most this share");
        v("min_gain", min_gain,
          "two models must explain this much larger a share of the points than one");
        v("max_points", max_points, "points used per evaluation");
        v("round_enabled", round_enabled,
          "split round objects that one cylinder explains poorly into two cylinders");
    }
};

/// The models stage: fitting, verification, fallback meshes, and grouping by models.
struct ModelParams {
    /// A primitive explaining less than this share of its object's points is replaced [-];
    /// [0, 1].
    float min_inlier_ratio = 0.75f;
    /// A model must fit the size of its points: its bounding box's diagonal may exceed that of
    /// the points by at most this factor plus size_margin (hidden back faces make a model up to
    /// about 1.4 times its visible points); a larger one (a 79 cm cylinder for a mug) is
    /// rejected like a poor fit [-]; >= 1.
    float max_size_ratio = 1.6f;
    float size_margin = 0.02f;  ///< [m]; >= 0
    /// Rejected or poorly fitting primitives are replaced by a triangulated mesh of the object's
    /// points (section 5.4.2.3); off: they stay, marked not accepted.
    bool mesh_fallback = true;
    /// Triangulation of fallback meshes and of attached outlier points.
    GreedyTriangulationParams mesh{.search_radius = 0.025f, .max_hole_edges = 8};
    std::size_t mesh_max_points = 2000;  ///< triangulate at most this many (even stride); >= 3
    /// A kept primitive's points farther than its inlier threshold from its surface (a mug's
    /// handle) are triangulated and attached to its mesh when at least this many [points];
    /// 0 = never.
    std::size_t min_attached_points = 80;
    /// Box and cylinder fits sample by RSD (planar points for boxes, curved ones for cylinders)
    /// and, with part probabilities (a part-graph categoriser), weight sampling and scoring by
    /// each point's probability of the fitted shape (sections 5.4.1, 5.4.2.1; FitGuidance).
    bool guided_fits = false;
    RsdParams guided_rsd{};  ///< RSD of the guidance (neighbourhoods among the object's points)
    BoxFitParams box{};      ///< box models of box and flat objects
    /// Cylinder models of cylindrical objects and plates.
    CylinderModelParams cylinder = [] {
        CylinderModelParams p;
        p.sac.max_iterations = 800;
        return p;
    }();
    /// Surfaces of revolution (section 5.4.2.2) for cylindrical, spherical and "other" objects
    /// whose primitive explains too little (under min_inlier_ratio); kept when they explain more
    /// points than the primitive. The support plane's up is the axis prior.
    Switchable<RotationalFitParams> rotational = Switchable<RotationalFitParams>::With(
        [](RotationalFitParams& p) { p.max_tilt_deg = 20.0f; });
    /// Verification of every model against the frame seen from the cloud's sensor origin
    /// (section 4.2.4.3); a model with more than max_invalid_ratio of its surface in space the
    /// sensor saw through is rejected. The rejection share is above the library's: an open cup's
    /// or bowl's closed top lies in free space (the sensor sees into it) and makes about 10-15 %
    /// of a good cylinder's surface. Samples 1 cm apart, as the grid's cells.
    Switchable<VerificationParams> verification =
        Switchable<VerificationParams>::With([](VerificationParams& p) {
            p.sample_spacing = 0.01f;
            p.max_invalid_ratio = 0.25f;
        });
    ConcentricMergeParams concentric{};
    ContainedMergeParams contained{};
    StackedSplitParams stacked{};
    TouchingSplitParams touching{};
    /// The Poisson model of parts per object (section 5.4.1, Eq. 5.1) decides which objects may be
    /// several: the touching splits are tried only when the object's part count is at least
    /// several_min_ratio times as likely for two objects of its type as for one [-]; >= 0.
    float several_min_ratio = 0.5f;
    PartCountParams part_counts{};
    int num_threads = 0;  ///< objects modelled in parallel; 0 = all cores
    /// Throws InvalidArgument naming the first out-of-range field (a ParameterError with the
    /// sub-node's name, `concentric: ...`, for the nested ones).
    void Validate() const;
    /// Its parameters once each: configuration key (the field's name), field, meaning. A
    /// visitor reads or records them (io::ConfigSection::operator(); ReadPerceiveParams).
    template <typename V>
    void VisitParams(V& v) {
        v("min_inlier_ratio", min_inlier_ratio,
          "primitives explaining a smaller share of their points are replaced");
        v("max_size_ratio", max_size_ratio,
          "a model's bounding-box diagonal is at most this times its points' (plus size_margin)");
        v("size_margin", size_margin, "... plus this much [m]");
        v("mesh_fallback", mesh_fallback,
          "replace rejected primitives by a triangulated mesh of the object's points");
        v.Node("mesh", mesh);
        v("mesh_max_points", mesh_max_points, "triangulate at most this many points (even stride)");
        v("min_attached_points", min_attached_points,
          "outliers of a kept primitive (a handle) are meshed and attached from this many, 0 = "
          "never");
        v("guided_fits", guided_fits,
          "box/cylinder fits sample by RSD and weight by part-graph part probabilities");
        v.Node("guided_rsd", guided_rsd);
        v.Node("box", box);
        v.Node("cylinder", cylinder);
        v.Switch(
            "rotational", rotational,
            "surfaces of revolution for cylinder/sphere/other objects whose primitive fits poorly");
        v.Switch("verification", verification, "verify models against the frame's free space");
        v.Node("concentric", concentric);
        v.Node("contained", contained);
        v.Node("stacked", stacked);
        v.Node("touching", touching);
        v("several_min_ratio", several_min_ratio,
          "splits are tried when the part count is this much likelier for two objects");
        v.Node("part_counts", part_counts);
    }
};

/// Verification of a fitted primitive (shares of its surface samples, VerifyModel).
struct ModelVerificationSummary {
    float verified = 0.0f;
    float occluded = 0.0f;
    float invalid = 0.0f;
    bool accepted = true;  ///< invalid <= max_invalid_ratio
};

/// What a gripper needs to know about an object's model.
struct GraspSummary {
    /// Named sizes [m]: box (and mesh): length, width, height; cylinder: diameter, height;
    /// rotational: max_diameter, height.
    std::vector<std::pair<std::string, float>> dimensions;
    std::optional<Eigen::Vector3f> axis;  ///< cylinder and rotational models
    /// Smallest extent of the model's mesh across any horizontal direction (in the support
    /// plane); without a plane the smallest side of its oriented bounding box [m].
    float graspable_width = 0.0f;
};

/// The model of one object: at most one of box / cylinder / rotational is set; none when the
/// primitive was replaced by a mesh of the object's points (`replaced` names it).
struct ObjectModel {
    std::optional<BoxModel> box;
    std::optional<CylinderModel> cylinder;
    std::optional<RotationalModel> rotational;
    TriangleMesh mesh;
    std::string replaced;                ///< type of the replaced primitive, empty if none
    std::string replace_reason;          ///< "inlier_ratio", "size" or "verification"
    float replaced_inlier_ratio = 0.0f;  ///< the replaced primitive's inlier_ratio
    std::optional<ModelVerificationSummary> verification;  ///< of the fitted primitive
    bool accepted = true;             ///< the primitive passed the inlier and verification checks
    std::size_t attached_points = 0;  ///< outlier points triangulated onto the model
    std::size_t attached_triangles = 0;  ///< their triangles in `mesh`
    GraspSummary grasp;
};

/// One perceived object: its points and parts (segmentation), category (categorisation) and
/// model (this stage).
struct PerceivedObject {
    int id = 0;       ///< 1-based, as in labels.pcd's `object` field
    Indices indices;  ///< the object's points, ascending
    std::vector<Indices> parts;
    /// Per part (same order as `parts`), the part-graph categoriser's distribution; empty with the
    /// rule-based categoriser.
    std::vector<CategoryDistribution> part_probabilities;
    CategoryResult category;
    /// The category was set from the kept model (CategorizeByModels), not by the experts.
    bool category_from_model = false;
    Eigen::Vector3f centroid = Eigen::Vector3f::Zero();
    ObjectModel model;
};

/// The model of one object (indices, parts and category set) in the frame `cloud` (its sensor
/// origin is the viewpoint): the primitive of its category, verified against the frame, replaced
/// by a mesh of its points when it explains too little or is rejected, outliers attached, and its
/// grasp summary. `plane` is the support plane (zero for none). Throws InvalidArgument for bad
/// parameters.
ObjectModel ModelObject(const PointCloud& cloud, const PerceivedObject& object,
                        const Eigen::Vector4f& plane, const ModelParams& params);

/// ModelObject for the objects `which` (indices into `objects`; empty = all), in parallel over
/// the objects (params.num_threads); the result does not depend on the thread count.
void ModelObjects(const PointCloud& cloud, std::vector<PerceivedObject>& objects,
                  const Eigen::Vector4f& plane, const ModelParams& params,
                  std::span<const std::size_t> which = {});

}  // namespace multicue
