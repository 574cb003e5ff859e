#pragma once
/// \file Furniture detection by part configurations (thesis section 4.2): the pipeline over one
/// or more registered scans.
///
///   parts      per view: world frame, floor cut, normals, region growing, 24 features (4.2.1)
///   votes      per view: word activations and Hough votes (Eqs. 4.1-4.4)
///   selection  the votes of all views merged (4.2.5.3), maxima in class-width windows,
///              class thresholds, overlapping same-class hypotheses reduced (4.2.4.2)
///   fitting    per hypothesis: upright RANSAC over the class's CAD models, ICP (4.2.4.3)
///   verify     coverage >= 50 %, not in the free space of any scan; fitted footprints that
///              overlap keep the stronger detection
///
/// PrepareFurnitureScene does the per-view work once, so that the selection and the fitting can
/// run on any subset of the views (single views against merged views) and with other settings.

#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "multicue/core/point_cloud.hpp"
#include "multicue/mapping/furniture_fit.hpp"
#include "multicue/recognition/furniture_model.hpp"
#include "multicue/recognition/furniture_parts.hpp"
#include "multicue/recognition/furniture_voting.hpp"

namespace multicue {

/// One scan and its pose in a z-up world frame whose floor lies at z = 0 (unless the part
/// parameters estimate the floor).
struct FurnitureView {
    const PointCloud* scan = nullptr;
    Eigen::Isometry3f T_world_sensor = Eigen::Isometry3f::Identity();
};

/// The extent of a detected piece from the scan: a CAD model of another size than the piece, fitted
/// to one end of it, centres the detection off the piece's centre. The parts of the scans that lie
/// mostly within the fitted model's footprint (grown by `margin`) belong to the piece; where they
/// reach beyond the model's box along one of its horizontal axes, the box grows to them (by at
/// most max_growth of the model's size on that side). A model larger than the piece, fitted over
/// one end of it, reaches beyond the piece's parts: there the box shrinks towards them (never
/// inside them) as far as the scans saw free space or other pieces and walls take the space,
/// slice by slice; a side the scans did not see stays, since it looks the same as a side that is
/// not there. Only the reported box and centre change; the tests, the verifier and the overlaps
/// judge the fitted model.
struct FurniturePieceParams {
    /// Measure the piece's box at all (grow it, and shrink it when `shrink`); off: the fitted
    /// model's box
    bool grow = true;
    /// Shrink where the box reaches beyond the parts into observed free space or space other
    /// pieces take (needs either)
    bool shrink = true;
    float slice = 0.05f;  ///< slices of this width are cut off one after another [m], > 0
    /// A slice goes when at least this share of its samples (5 cm apart, at three heights up to
    /// the parts' top) lies in free space, (0, 1]
    float free_share = 0.5f;
    /// Detection: the fitted models of the more likely accepted pieces take their footprints'
    /// space (FurnitureTakenSpace); a piece's box keeps out of it
    bool taken = true;
    /// Detection: the views' walls (FindFurnitureWalls) take a band of 5 cm on either side of
    /// their planes, as other pieces take their space
    bool walls = true;
    float member_share = 0.6f;  ///< share of a part's points within the grown footprint, (0, 1]
    float margin = 0.1f;        ///< footprint grown by this to take in parts [m], >= 0
    float min_growth = 0.05f;   ///< parts reaching less far beyond the box leave it [m], >= 0
    float max_growth = 0.5f;    ///< at most this times the model's size per side [-], >= 0
    /// Throws InvalidArgument naming the first out-of-range field.
    void Validate() const;
};

struct FurnitureDetectionParams {
    FurnitureVotingParams voting{};
    /// Hypotheses down to 0.3 of their class threshold are fitted: the fit and the verifier
    /// judge them. Without verification, 1 keeps those above the class thresholds only
    FurnitureSelectionParams selection{.threshold_scale = 0.3f};
    FurnitureFitParams fit{};
    /// With verify: every class is also fitted where a hypothesis of another class reaches its
    /// class threshold (FurnitureSelectionParams::other_classes); such a fit names a piece only
    /// where no fit of a class voted for there does. Off: on the validation rooms it found one
    /// piece more and added three false detections (eval/README.md)
    bool other_classes = false;
    bool verify = true;      ///< fit and verify CAD models; off: hypotheses are detections
    bool free_space = true;  ///< with verify: the free-space test (one occupancy map per scan)
    /// Fitted footprints of two accepted detections that overlap by more than this share of the
    /// smaller one are inconsistent: the weaker goes, (0, 1]
    float max_overlap = 0.3f;
    bool cross_class = true;  ///< apply max_overlap across classes too (one piece, one class)
    /// Across classes, the share of one fitted model's surface lying within
    /// surface_overlap_distance of the other's (the larger of the two shares) is compared with
    /// max_overlap instead of the footprints: a chair pushed under a table shares its footprint
    /// but no surface with it; two models of one piece share theirs
    bool cross_class_surfaces = true;
    float surface_overlap_distance = 0.05f;  ///< [m], > 0
    /// Of overlapping fitted detections, keep the one whose model explains the scan best rather
    /// than the one with the strongest votes (the votes find the piece, the models name it)
    bool class_by_fit = true;
    /// Learned verification: when the model has a verifier (FurnitureModel::verifier), every fit
    /// gets the verifier's probability of being right (FurnitureDetection::confidence); fits
    /// below min_confidence are rejected, the confidence is the detection's score and decides
    /// which of overlapping fits stays
    bool learned = true;
    /// [0, 1]; 0.35: the lowest cut at which the merged precision of the validation rooms and
    /// the library folds together stays at 0.9, with fit_models 3 (eval/README.md)
    float min_confidence = 0.35f;
    /// The same for a single view, [0, 1]: the verifier, which does not know how many views a
    /// fit saw, is less often right about a fit to one scan; 0.4 chosen the same way on single
    /// scans
    float min_confidence_single = 0.4f;
    /// With learned verification, the verifier also judges the fits that the coverage,
    /// free-space and wall tests rejected (its features hold the same shares): it replaces the
    /// tests. Off: a fit must pass the tests and the verifier
    bool learned_tests = true;
    /// Parts whose centre lies further from a hypothesis than half its class's length plus this
    /// are left out of its fit [m], >= 0
    float support_margin = 0.3f;
    /// With verify: the best poses of this many CAD models of the class are finished per
    /// hypothesis (FitFurnitureModels), each a fit of its own; overlapping fits of one piece are
    /// then one detection, the most likely (or best explaining) staying. A model of the piece's
    /// size placed on it can then win over a longer one that the search preferred because it
    /// also covers a neighbour. 1: the best model's fit alone (the thesis), >= 1; 3 found more
    /// pieces on the validation rooms and library folds (eval/README.md)
    int fit_models = 3;
    /// Reject hypotheses and fits behind the views' walls (margin and share: fit.wall_margin,
    /// fit.max_behind_share)
    bool walls = true;
    float min_wall_length = 1.0f;  ///< upright planes this long (and taller than any piece) [m]
    /// The reported box and centre of each accepted detection grown to the scan's parts of the
    /// piece (MeasureFurniturePiece)
    FurniturePieceParams piece{};
    int num_threads = 0;  ///< 0 = all cores; never changes the result
    /// Throws InvalidArgument naming the first out-of-range field.
    void Validate() const;
};

/// How much two fitted models are one surface: the larger of the shares of one model's points
/// (CAD point clouds `a` and `b` placed by T_a and T_b; about 2000 of each) that have a point of
/// the other in their cell or a neighbouring one (cells of `distance`, so within one to two
/// distances). 0 when either has no finite points. Throws InvalidArgument for distance <= 0 or
/// poses that are not finite.
float SharedSurfaceShare(const PointCloud& a, const Eigen::Isometry3f& T_a, const PointCloud& b,
                         const Eigen::Isometry3f& T_b, float distance);

/// The views after the per-view work: their parts and, when wanted, occupancy maps.
struct FurnitureScene {
    std::vector<FurnitureParts> views;
    std::vector<std::vector<FurnitureVote>> votes;  ///< per view
    std::vector<FurnitureFreeSpace> free_space;     ///< per view; empty without the test
    std::vector<std::vector<FurnitureWall>> walls;  ///< per view
    double parts_ms = 0.0;                          ///< ExtractFurnitureParts over all views [ms]
    double votes_ms = 0.0;                          ///< CastFurnitureVotes over all views [ms]
    double occupancy_ms = 0.0;                      ///< occupancy maps [ms]
};

/// Parts, votes and (with verify and free_space) occupancy maps of every view. The part
/// parameters are the model's (the training views went through the same ones). Throws
/// InvalidArgument for bad parameters, a null scan or a non-finite pose.
FurnitureScene PrepareFurnitureScene(const std::vector<FurnitureView>& views,
                                     const FurnitureModel& model,
                                     const FurnitureDetectionParams& params);

/// How the scan points around a fit lie in the fitted model's frame, whatever the model's surface
/// looks like: the shape of the piece against the size of the model (features of the learned
/// verifier). Points "inside" lie within the model's footprint grown by 10 cm, at any height.
struct FurnitureShapeEvidence {
    float inside_share = 0.0f;  ///< the fit's support points inside [-]
    float top = 0.0f;           ///< 95th percentile of the inside points' heights [m]
    float top_ratio = 0.0f;     ///< top / the model's height [-]
    float span_x = 0.0f;     ///< 5-95 % spread of the inside points along the model's x / its depth
    float span_y = 0.0f;     ///< the same along y / the model's width
    float low_share = 0.0f;  ///< inside points below a quarter of the model's height [-]
    /// Support points 10-30 cm beyond the footprint per inside point: the piece goes on where the
    /// model ends [-]
    float beyond = 0.0f;
};

/// The shape evidence of `points` (world frame) against CAD model `cad` placed by `T` (upright).
/// Zeros without points.
FurnitureShapeEvidence MeasureFurnitureShape(const PointCloud& points, const FurnitureCad& cad,
                                             const Eigen::Affine3f& T);

/// Floor space that another detected piece takes: its fitted model's box `box` in the frame
/// `T_world_box` (upright).
struct FurnitureTakenSpace {
    Eigen::Isometry3f T_world_box = Eigen::Isometry3f::Identity();
    Eigen::AlignedBox3f box;
    /// Whether the floor point `xy` (world frame) lies within the box's footprint.
    bool Contains(const Eigen::Vector2f& xy) const;
};

/// The floor band a wall takes: `half_width` on either side of its plane, along its extent
/// (FurnitureWall::lo to hi). Throws InvalidArgument for half_width <= 0.
FurnitureTakenSpace FurnitureWallBand(const FurnitureWall& wall, float half_width);

/// The box of the piece that `fit` explains, in the frame of fit.T_world_model [m]: the fitted
/// model's box (stretched by fit.scale), grown along the model's horizontal axes to the parts of
/// `views` that belong to the piece and shrunk towards them through the free space of `free`
/// (FurniturePieceParams; no shrinking without free or taken space). The space of `taken` belongs
/// to other pieces: a part lying mostly there is not this piece's, and the box shrinks through it
/// as through free space. Empty without a fitted model. Throws InvalidArgument for bad
/// parameters.
Eigen::AlignedBox3f MeasureFurniturePiece(const std::vector<const FurnitureParts*>& views,
                                          const FurnitureCad& cad, const FurnitureFit& fit,
                                          const FurniturePieceParams& params,
                                          const std::vector<const FurnitureFreeSpace*>& free = {},
                                          const std::vector<FurnitureTakenSpace>& taken = {});

/// The piece's box (MeasureFurniturePiece with `params`; the fitted model's box without growth)
/// into `box`, and the centre on the floor [m] that it gives: the fitted model's centre moved by
/// as much as the box's centre moved from the model's box's. The model's centre without a box.
Eigen::Vector2f FurniturePieceCentre(const std::vector<const FurnitureParts*>& views,
                                     const FurnitureCad& cad, const FurnitureFit& fit,
                                     const FurniturePieceParams& params, Eigen::AlignedBox3f& box,
                                     const std::vector<const FurnitureFreeSpace*>& free = {},
                                     const std::vector<FurnitureTakenSpace>& taken = {});

/// One detection (or a rejected hypothesis).
struct FurnitureDetection {
    int cls = 0;
    std::string category;
    FurnitureHypothesis hypothesis;  ///< from the vote space
    bool fitted = false;             ///< a CAD model was fitted
    FurnitureFit fit;
    /// Centre on the floor [m]: of the hypothesis; once fitted, of the fitted model; once
    /// accepted, of the piece's box (`box`)
    Eigen::Vector2f centre = Eigen::Vector2f::Zero();
    /// The piece's box in the frame of fit.T_world_model (MeasureFurniturePiece) [m]: the fitted
    /// model's box, grown to the scan's parts of the piece for an accepted detection; empty
    /// without a fit
    Eigen::AlignedBox3f box;
    /// The hypothesis's score over its class threshold; for a fitted detection (verify) times
    /// 0.5 + coverage - free share, so that a piece explained well by a model that claims no
    /// free space outranks one that is not (and wins where two overlap); with learned
    /// verification the confidence
    float score = 0.0f;
    /// Share of the fitted model's surface within surface_overlap_distance (one to two cells)
    /// of the scan points it was fitted to
    float explained = 0.0f;
    FurnitureShapeEvidence shape;  ///< the support points against the fitted model
    /// Probability that the fit is right by the model's verifier; -1 when not computed
    float confidence = -1.0f;
    bool accepted = false;
    /// "", "coverage", "free_space", "no_fit", "behind_wall", "confidence" or "overlap"
    std::string rejection;
};

/// Names of the verifier's features, in the order of FurnitureVerifierFeatures: the vote score
/// and parts of the hypothesis, the fit's coverage, free and wall shares, explained surface,
/// support points, refinement and shift from the votes, the shape evidence, and one indicator
/// per class.
std::vector<std::string> FurnitureVerifierFeatureNames(const FurnitureModel& model);
/// The verifier's feature row of a fitted detection.
std::vector<float> FurnitureVerifierFeatures(const FurnitureDetection& d,
                                             const FurnitureModel& model);
/// The row for a verifier trained on the features `names` (a selection of
/// FurnitureVerifierFeatureNames in any order; verifiers of older models lack the shape
/// evidence). Throws InvalidArgument for a name that is not one of them.
std::vector<float> FurnitureVerifierFeatures(const FurnitureDetection& d,
                                             const FurnitureModel& model,
                                             const std::vector<std::string>& names);

struct FurnitureDetectionResult {
    std::vector<FurnitureDetection> detections;  ///< accepted, strongest first
    std::vector<FurnitureDetection> rejected;    ///< rejected hypotheses, strongest first
    std::size_t votes = 0;
    double selection_ms = 0.0;          ///< merging and selection [ms]
    double fit_ms = 0.0;                ///< fitting and verification of all hypotheses [ms]
    std::size_t fitted_hypotheses = 0;  ///< hypotheses a model was fitted to (fit_ms's count)
};

/// Detections from the views `subset` of `scene` (empty: all, merged). `context` is needed with
/// verify (InvalidArgument without it) and must belong to `model`.
FurnitureDetectionResult DetectFurniture(const FurnitureScene& scene,
                                         const std::vector<int>& subset,
                                         const FurnitureModel& model,
                                         const FurnitureFitContext* context,
                                         const FurnitureDetectionParams& params);

/// PrepareFurnitureScene and DetectFurniture over all views.
FurnitureDetectionResult DetectFurniture(const std::vector<FurnitureView>& views,
                                         const FurnitureModel& model,
                                         const FurnitureFitContext* context,
                                         const FurnitureDetectionParams& params);

/// The walls among a view's parts: parts reaching above `max_top` [m] of which at least 95 % of
/// the points lie within 10 cm of one upright plane (a few stray points around a corner or of an
/// object touching the wall are allowed), at least `min_length` [m] long. Their normals point to
/// the view's sensor. Throws InvalidArgument for a max_top that is not finite or min_length <= 0.
std::vector<FurnitureWall> FindFurnitureWalls(const FurnitureParts& view, float max_top,
                                              float min_length);

/// Area of the intersection of two convex polygons (counter-clockwise) [m^2].
float ConvexIntersectionArea(const std::vector<Eigen::Vector2f>& a,
                             const std::vector<Eigen::Vector2f>& b);

}  // namespace multicue
