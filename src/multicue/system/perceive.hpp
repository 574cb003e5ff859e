#pragma once
/// \file The table-top perception pipeline behind `multicue perceive`: normals, support plane,
/// object hypotheses above it, parts, first categories and primitive models (thesis sections 2.4,
/// 3.2.1, 4.2.1). Every parameter lives in PerceiveParams; ReadPerceiveParams maps it to a
/// parameter file.

#include <array>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "multicue/core/point_cloud.hpp"
#include "multicue/core/triangle_mesh.hpp"
#include "multicue/io/config.hpp"
#include "multicue/recognition/geometric_category.hpp"
#include "multicue/recognition/part_graph_model.hpp"
#include "multicue/reconstruction/fit_guidance.hpp"
#include "multicue/reconstruction/part_count_model.hpp"
#include "multicue/reconstruction/primitive_models.hpp"
#include "multicue/reconstruction/rotational_model.hpp"
#include "multicue/reconstruction/verification.hpp"
#include "multicue/segmentation/convexity_split.hpp"
#include "multicue/segmentation/euclidean_clustering.hpp"
#include "multicue/segmentation/occlusion_merge.hpp"
#include "multicue/segmentation/polygonal_prism.hpp"
#include "multicue/segmentation/region_growing.hpp"
#include "multicue/segmentation/support_plane.hpp"
#include "multicue/surface/greedy_triangulation.hpp"
#include "multicue/surface/normals.hpp"

namespace multicue {

struct PerceiveParams {
    /// Normals of organized frames (image-space fast path).
    /// A 15x15 window read every 3rd pixel (about 2.7 cm at 1 m): wide enough to smooth Kinect
    /// noise, narrow enough to keep the faces of a 9 cm box apart.
    OrganizedNormalParams organized_normals{.half_window = 7};
    /// Normals of unorganized clouds (k-d tree).
    NormalParams normals{.k = 20, .radius = 0.0f, .viewpoint = std::nullopt, .num_threads = 0};
    SupportPlaneParams support{};
    PrismParams prism{.min_height = 0.008f, .max_height = 0.5f};
    float cluster_tolerance = 0.015f;        ///< object hypotheses: Euclidean tolerance [m]
    std::size_t min_object_points = 150;     ///< smaller clusters are not objects [points]
    std::size_t max_object_points = 200000;  ///< larger clusters are not objects [points]
    int organized_half_window = 2;  ///< organized clustering reach; bridges 1-pixel gaps [px]
    /// Over-segmentation into parts (section 4.2.1). The k cap keeps dense RGB-D objects cheap:
    /// with thousands of points within 5 cm, the nearest ones already decide connectivity.
    RegionGrowingParams parts{.k = 16};
    bool split_concave = true;  ///< split hypotheses along concave part borders (stacked objects)
    ConvexitySplitParams convexity{};
    bool merge_occluded = true;  ///< join fragments of objects split by a nearer occluder
    OcclusionMergeParams occlusion{};
    /// First, rule-based categories; fewer samples than the defaults of a one-off call, which
    /// keeps a frame within budget at the same accuracy on mOSD.
    CategoryParams category{.max_points = 1500, .max_iterations = 400};
    /// "rules" (CategorizeObject) or "part-graph" (part-graph hashing, docs/part-graph.md: the
    /// categories, probabilities and per-point labels then come from the parts' votes; the rule
    /// result stays the input of the model fits' "upright" details only), or "part-graph+rules"
    /// (both: per category rules^(1 - w) * part-graph^w, w = part_graph_weight, each
    /// distribution floored at 0.01 first, then normalised), or "part-graph+rules+cluster" (three
    /// experts: rules^a * part-graph^b * cluster^c, (a, b, c) = expert_weights normalised, cluster
    /// being the model's whole-object k-NN on GRSD- and VFH, PartGraphModel::ClassifyCluster, k =
    /// cluster_k; without cluster rows in the model, rules and part-graph alone), or
    /// "stacked" (the model's level-1 classifier over the three experts and the rules' geometric
    /// evidence, CategoryStacker; the model must have been trained with stacker scenes).
    std::string categoriser = "rules";
    std::size_t cluster_k = 5;  ///< neighbours of the whole-object expert [-]; >= 1
    /// Part-graph model file; empty = `part_graph` must be set (the CLI then uses the default
    /// model, trained once and cached).
    std::string part_graph_model;
    std::shared_ptr<const PartGraphModel> part_graph;  ///< loaded model (wins over the file)
    /// Part-graph recognition as perceive runs it: parts grouped by object, and "other" with a
    /// third of the weight of the other categories. The balanced votes treat every category as
    /// equally likely, while "other" (pitchers, tools, irregular shapes) is the rarest category
    /// on tables and the one whose training shapes overlap most with cups, mugs and bottles
    /// (docs/part-graph.md, "Current defaults on fifty scenes").
    PartGraphRecognitionParams part_graph_recognition = [] {
        PartGraphRecognitionParams p;
        p.category_priors[static_cast<std::size_t>(Category::kOther)] = 0.3f;
        return p;
    }();
    float part_graph_weight = 0.4f;  ///< weight w of the part-graph votes in "part-graph+rules"
    /// Weights of the rules, the part-graph and the cluster expert in "part-graph+rules+cluster"
    /// (normalised to sum 1; BlendThreeExperts). Chosen on simulated clutter scenes of seeds
    /// other than those part_graph_eval reports (docs/part-graph.md, "Weighting the three
    /// experts"); equal weights were the default before.
    Eigen::Vector3f expert_weights{0.25f, 0.65f, 0.10f};
    BoxFitParams box{};                  ///< box models of box and flat objects
    CylinderModelParams cylinder = [] {  ///< cylinder models of cylindrical objects
        CylinderModelParams p;
        p.sac.max_iterations = 800;
        return p;
    }();
    /// Surfaces of revolution (section 5.4.2.2) for cylindrical, spherical and "other" objects
    /// whose primitive explains too little (under min_model_inlier_ratio); kept when they explain
    /// more points than the primitive. The support plane's up is the axis prior.
    bool try_rotational = true;
    RotationalFitParams rotational{.max_tilt_deg = 20.0f};
    /// Verification of every model against the frame seen from the cloud's sensor origin
    /// (section 4.2.4.3); a model with more than verification.max_invalid_ratio of its surface in
    /// space the sensor saw through is rejected.
    /// The rejection share is above the library's: an open cup's or bowl's closed top lies in
    /// free space (the sensor sees into it) and makes about 10-15 % of a good cylinder's surface.
    /// Samples 1 cm apart, as the grid's cells.
    bool verify_models = true;
    VerificationParams verification{.sample_spacing = 0.01f, .max_invalid_ratio = 0.25f};
    /// Box and cylinder fits sample by RSD (planar points for boxes, curved ones for cylinders)
    /// and, with a part-graph categoriser, weight sampling and scoring by each point's part
    /// probability of the fitted shape (sections 5.4.1, 5.4.2.1; FitGuidance).
    bool guided_fits = false;
    RsdParams guided_rsd{};  ///< RSD of the guidance (neighbourhoods among the object's points)
    /// A primitive explaining less than this share of its object's points is replaced [-].
    float min_model_inlier_ratio = 0.75f;
    /// Rejected or poorly fitting primitives are replaced by a triangulated mesh of the object's
    /// points (section 5.4.2.3); off = they stay, marked not accepted.
    bool mesh_fallback = true;
    /// Triangulation of fallback meshes and of attached outlier points.
    GreedyTriangulationParams model_mesh{.search_radius = 0.025f, .max_hole_edges = 8};
    std::size_t model_mesh_max_points = 2000;  ///< triangulate at most this many (even stride)
    /// A kept primitive's points farther than its inlier threshold from its surface (a mug's
    /// handle) are triangulated and attached to its mesh when at least this many [points].
    std::size_t min_attached_points = 80;
    /// Grouping by models (section 5.4.1): two objects whose cylinders share their axis (within
    /// concentric_angle_deg and concentric_distance), have radii within concentric_radius_ratio of
    /// each other and overlap along the axis are one object seen as two surfaces (the inside and
    /// the outside of a pot or bowl); they are merged and categorised and modelled again.
    bool merge_concentric = true;
    float concentric_angle_deg = 8.0f;      ///< [deg]
    float concentric_distance = 0.02f;      ///< axis to axis [m]
    float concentric_radius_ratio = 0.25f;  ///< |r1 - r2| / max(r1, r2) [-]
    /// Contained objects: an object with at least contained_min_share of its points inside the
    /// solid of another (larger) object's accepted cylinder or surface of revolution, enlarged by
    /// contained_margin, is part of it (the bottom inside a bowl, its outer wall, a mug's handle).
    bool merge_contained = true;
    float contained_margin = 0.015f;   ///< [m]
    float contained_min_share = 0.8f;  ///< (0, 1] [-]
    /// Stacked boxes: a box or flat object with two horizontal faces (parts with normals within
    /// 10 degrees of up, at least stack_min_face_points each) at heights at least stack_min_step
    /// apart, the lower one above the table, is split at the lower face's height when the two
    /// upright boxes explain a larger share of the points than one box (by stack_min_gain).
    bool split_stacked = true;
    std::size_t stack_min_face_points = 200;  ///< [points]
    float stack_min_step = 0.02f;             ///< [m]
    float stack_min_gain = 0.05f;             ///< inlier ratio gain of two boxes over one [-]
    /// Touching boxes: a box or flat object that one upright box explains poorly (below
    /// min_model_inlier_ratio) is tried as every split of its touching_max_parts largest parts
    /// (of at least touching_min_part_points each) into two groups, each an upright box; the best
    /// split is kept when each box explains at least min_model_inlier_ratio of its group, the two
    /// solids overlap by at most touching_max_overlap (of either box's volume), and together they
    /// explain at least touching_min_gain more of the object's points than one box.
    bool split_touching = true;
    std::size_t touching_min_part_points = 100;  ///< [points]
    int touching_max_parts = 8;                  ///< [parts]; 2 to 12
    float touching_max_overlap = 0.15f;          ///< [-]
    float touching_min_gain = 0.1f;              ///< [-]
    std::size_t touching_max_points = 3000;      ///< points used per evaluation [points]
    /// Touching round objects (a can standing in a bowl): a sphere, cylinder or other object
    /// that one cylinder explains poorly gets a cylinder for the parts it explains (most of
    /// their points within the cylinder's inlier threshold) and one for the remaining parts;
    /// the two are kept as objects when each explains min_model_inlier_ratio of its parts,
    /// together touching_min_gain more of the points than one, and they are not the inside and
    /// outside of one container (see merge_concentric).
    bool split_touching_round = true;
    /// The Poisson model of parts per object (section 5.4.1, Eq. 5.1) decides which objects may be
    /// several: the touching splits are tried only when the object's part count is at least
    /// several_min_ratio times as likely for two objects of its type as for one.
    PartCountParams part_counts{};
    float several_min_ratio = 0.5f;  ///< [-]; >= 0
    int num_threads = 0;             ///< 0 = all cores; overrides the stages' own thread counts
};

/// Reads (or, with a dump section, records) every parameter.
void ReadPerceiveParams(io::ConfigSection& config, PerceiveParams& params);

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
    std::string replace_reason;          ///< "inlier_ratio" or "verification"
    float replaced_inlier_ratio = 0.0f;  ///< the replaced primitive's inlier_ratio
    std::optional<ModelVerificationSummary> verification;  ///< of the fitted primitive
    bool accepted = true;             ///< the primitive passed the inlier and verification checks
    std::size_t attached_points = 0;  ///< outlier points triangulated onto the model
    std::size_t attached_triangles = 0;  ///< their triangles in `mesh`
    GraspSummary grasp;
};

struct PerceivedObject {
    int id = 0;       ///< 1-based, as in labels.pcd's `object` field
    Indices indices;  ///< the object's points, ascending
    std::vector<Indices> parts;
    /// Per part (same order as `parts`), the part-graph categoriser's distribution; empty with the
    /// rule-based categoriser.
    std::vector<std::array<float, kNumCategories>> part_probabilities;
    CategoryResult category;
    Eigen::Vector3f centroid = Eigen::Vector3f::Zero();
    ObjectModel model;
};

struct PerceiveResult {
    std::size_t points = 0;  ///< points of the input (NaN included)
    SupportPlane support;    ///< support.found = false: no table, objects from the whole cloud
    std::vector<PerceivedObject> objects;
    std::vector<std::uint32_t> point_objects;    ///< per input point: object id or 0
    std::vector<std::uint8_t> point_categories;  ///< per input point: category index or 0
    std::vector<std::pair<std::string, double>> timings_ms;  ///< stage -> wall time, in order
};

/// The model of one object (indices and category set) in the frame `cloud` (its sensor origin is
/// the viewpoint): the primitive of its category (box, cylinder, or a surface of revolution when
/// that explains more), verified against the frame, replaced by a mesh of its points when it
/// explains too little or is rejected, outliers attached, and its grasp summary. `plane` is the
/// support plane (zero for none). Used by Perceive; throws InvalidArgument for bad parameters.
ObjectModel ModelObject(const PointCloud& cloud, const PerceivedObject& object,
                        const Eigen::Vector4f& plane, const PerceiveParams& params);

/// The whole-object expert as perceive runs it: the model's cluster k-NN (params.cluster_k) on
/// the object's GRSD- and VFH descriptor, weighted by the part-graph category priors; all zero
/// when the model has no cluster rows.
CategoryDistribution ClusterExpert(const PartGraphModel& model, const PointCloud& cloud,
                                   const Indices& object, const PerceiveParams& params);

/// The part-graph expert as perceive runs it: one graph over the parts of all `objects`, each
/// part grouped with its object (params.part_graph_recognition), up from `plane` (a, b, c, d;
/// zero when unknown).
struct PartGraphVotes {
    std::vector<std::vector<CategoryDistribution>> parts;  ///< per object, one per part
    std::vector<CategoryDistribution> objects;  ///< per object: point-weighted merge of its parts
};
PartGraphVotes VotePartGraph(const PartGraphModel& model, const PointCloud& cloud,
                             const std::vector<PerceivedObject>& objects,
                             const Eigen::Vector4f& plane, const PerceiveParams& params);

/// "part-graph+rules+cluster": rules^a * part-graph^b * cluster^c, normalised, with (a, b, c) =
/// `weights` / their sum and each probability floored at 0.01 first; an all-zero cluster expert
/// (a model without cluster rows) leaves rules and part-graph, their weights renormalised.
/// Throws InvalidArgument for negative, non-finite or all-zero weights.
CategoryDistribution BlendThreeExperts(const CategoryDistribution& rules,
                                       const CategoryDistribution& part_graph,
                                       const CategoryDistribution& cluster,
                                       const Eigen::Vector3f& weights = Eigen::Vector3f::Ones());

/// Normals as perceive computes them, unless `cloud` has normals and curvature already:
/// organized frames take the image-space path for the points `roi` only, others k-NN PCA.
void EnsurePerceiveNormals(PointCloud& cloud, const Indices& roi, const PerceiveParams& params);

/// Runs the pipeline. The cloud must hold at least one finite point (DataError otherwise); normals
/// are computed unless the cloud has them. Throws InvalidArgument for bad parameters.
PerceiveResult Perceive(const PointCloud& cloud, const PerceiveParams& params);

}  // namespace multicue
