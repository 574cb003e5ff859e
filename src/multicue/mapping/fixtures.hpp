#pragma once
/// \file Fixtures of furniture faces (thesis section 4.1.2): the points on and in the polygonal
/// prism in front of each face are measured against the face's local background
/// (fixture_evidence.hpp); those standing out of it are clustered by Euclidean distance, clusters
/// too big to grasp are rejected, and RANSAC line and circle fits, with the footprint's elongation,
/// tell handles (long, on a line) from knobs (compact, round). Every candidate is described by a
/// row of measurements; a classifier trained on simulated kitchens decides what it is, or, without
/// one, the rules of this file (how far it stands out, its shape, the face around it).

#include <cstddef>
#include <cstdint>
#include <vector>

#include "multicue/core/point_cloud.hpp"
#include "multicue/mapping/fixture_evidence.hpp"
#include "multicue/mapping/room_structure.hpp"
#include "multicue/mapping/semantic_map.hpp"
#include "multicue/ml/classifier.hpp"

namespace multicue::mapping {

struct FixtureParams {
    /// Points this close to a large face lie on it (they are its samples, not another face's) [m]
    float min_height = 0.012f;
    float max_height = 0.10f;  ///< farthest a fixture point lies from its face [m]
    /// Height noise of a point at range r: max(noise_floor, range_noise * r^2) [1/m]
    float range_noise = 0.0f;
    float noise_floor = 0.003f;     ///< [m]
    float background_cell = 0.03f;  ///< cell of the local background's median heights [m]
    int background_radius = 3;      ///< the background is the median over (2r + 1)^2 cells
    int background_passes = 2;      ///< passes without the samples standing out (>= 1)
    float residual_cell = 0.01f;    ///< heights above the background are averaged per cell [m]
    /// A candidate point's cell stands above the background by at least this [m]
    float min_residual = 0.012f;
    /// ... and by this many standard deviations of its cell's mean height [-]
    float residual_sigmas = 3.0f;
    /// A point standing out by this many standard deviations (and min_residual) is a candidate
    /// whatever its cell's mean [-]
    float point_sigmas = 2.5f;
    /// Surround of a candidate: face samples from surround_inner to surround_outer beyond its
    /// footprint's box, within background_tolerance of the background [m]
    float surround_inner = 0.01f;
    float surround_outer = 0.05f;         ///< [m]
    float background_tolerance = 0.008f;  ///< at least twice the height noise [m]
    /// Appearance cue: a point whose colour (distance in grey level and chroma,
    /// AppearanceContrast) or scaled intensity differs from its face's local background (the
    /// median over the same cells as the heights) by at least this is a candidate when it also
    /// stands contrast_min_residual out of the face; 0: off [0..255]
    float min_contrast = 0.0f;
    float contrast_min_residual = 0.004f;  ///< [m]
    /// With a classifier: a candidate is a fixture when P(handle) + P(knob) reaches this [-]
    float min_confidence = 0.5f;
    /// With a classifier: a candidate below min_confidence but with at least this confidence is
    /// a fixture too when no fixture lies within lone_clearance of it (a handle of a design the
    /// classifier has not seen, on a front that would otherwise have none); candidates are taken
    /// in order of confidence, each counting for the next. At min_confidence or above: off [-]
    float lone_min_confidence = 1.0f;
    float lone_clearance = 0.3f;       ///< between the axes of two fixtures (segments) [m]
    float face_margin = 0.02f;         ///< fixtures may reach this far beyond the face's extent [m]
    float cluster_tolerance = 0.015f;  ///< Euclidean clustering tolerance [m]
    float merge_gap = 0.025f;          ///< clusters whose boxes lie closer are one fixture [m]
    std::size_t min_points = 12;       ///< smaller clusters are noise [points]
    float max_diameter = 1.2f;         ///< larger clusters (box diagonal) are no handle [m]
    float max_protrusion_extent = 0.09f;  ///< larger extent along the face normal: no fixture [m]
    /// Rules: a fixture stands at least this far out of the face around it (local protrusion) [m]
    float min_protrusion = 0.029f;
    int min_sides = 3;  ///< rules: the face surrounds a fixture on this many sides at least
    /// Face points lie within this of a fixture's centre (in the face plane): fixtures are in
    /// front of the face, not beside it [m]
    float footprint_reach = 0.06f;
    /// Clusters with more than this share of points next to a plane of another orientation (the
    /// edge of a worktop above a face, a side panel beside it) are edges, not fixtures [-]
    float max_attached_share = 0.1f;
    float attach_cell = 0.02f;  ///< cell of the attachment test [m]
    /// Points of planar components at least this large and of another orientation than the face
    /// (a worktop, a side panel) are never fixture points [m^2]
    float min_blocking_area = 0.03f;
    float min_handle_length = 0.05f;  ///< a handle is at least this long [m]
    float min_elongation = 2.2f;      ///< length / width of a handle's footprint [-]
    float max_knob_size = 0.09f;      ///< largest extent of a knob [m]
    float min_knob_size = 0.015f;     ///< smallest extent of a knob across [m]
    float min_knob_roundness = 0.5f;  ///< width / length of a knob's footprint [-]
    /// Organized clouds: clusters within this many pixels of the image border are cut off by
    /// it and are not measured [px]
    int border_px = 3;
    float line_threshold = 0.008f;    ///< RANSAC line inlier distance [m]
    float circle_threshold = 0.005f;  ///< RANSAC circle inlier distance [m]
    std::uint64_t seed = 1;           ///< RANSAC seed
    /// Points and faces in parallel (0 = all cores); the result does not depend on it.
    int num_threads = 1;
    /// Throws InvalidArgument naming the first out-of-range field.
    void Validate() const;
};

/// A cluster in front of a face that did not become a fixture, and why.
struct RejectedCluster {
    Eigen::Vector3f center = Eigen::Vector3f::Zero();  ///< of its bounding box [m]
    std::size_t points = 0;
    /// "too large", "image border", "shape", "low", "not in front of the face", "attached to
    /// another plane", "classifier"
    const char* reason = "";
};

/// A cluster that was measured: its evidence and what became of it.
struct FixtureCandidate {
    Fixture fixture;           ///< measured (type by shape; indices, centre, direction, ...)
    FixtureEvidence evidence;  ///< the classifier's row
    bool accepted = false;     ///< became a fixture
    float confidence = 0.0f;   ///< P(handle) + P(knob) with a classifier, else 0 or 1
    const char* reason = "";   ///< why it was rejected ("" when accepted)
};

struct FixtureResult {
    std::vector<Fixture> fixtures;             ///< handles and knobs, ordered by face then position
    std::vector<RejectedCluster> rejected;     ///< the clusters dropped
    std::vector<FixtureCandidate> candidates;  ///< every measured cluster (training rows)
    Indices candidate_points;  ///< every point that stood out of its face's background
    /// Per point: the face (index into the components) it was measured against, -1 for none,
    /// and its height above that face's local background [m] (NaN for none).
    std::vector<std::int32_t> point_face;
    std::vector<float> point_residual;
    std::size_t too_large = 0;     ///< clusters rejected as too big to grasp
    std::size_t unclassified = 0;  ///< rejected for any other reason
};

/// Fixtures in front of the furniture faces (components labelled kFace) of `structure`.
/// `ranges` holds each point's distance to its sensor (empty: to cloud.sensor_origin).
/// `classifier` (trained on FixtureFeatureNames rows with classes among FixtureClassNames) decides
/// which candidates are fixtures; nullptr: the rules. Throws InvalidArgument for bad parameters,
/// ranges of the wrong size or a classifier trained on other columns or classes.
FixtureResult DetectFixtures(const PointCloud& cloud, const RoomFrame& frame,
                             const RoomStructure& structure, const FixtureParams& params = {},
                             const std::vector<float>& ranges = {},
                             const ml::Classifier* classifier = nullptr);

/// The lone candidates of FixtureParams::lone_min_confidence: every candidate not yet accepted
/// whose confidence reaches lone_min_confidence is accepted (reason cleared), most confident
/// first, when no accepted candidate's fixture (those accepted here included) lies within
/// lone_clearance of its fixture, measured between their axes (a handle's segment along its
/// length, a knob's centre). DetectFixtures calls it with a classifier when
/// lone_min_confidence < min_confidence. Throws InvalidArgument for bad parameters.
void AcceptLoneCandidates(const std::vector<FixtureCandidate*>& candidates,
                          const FixtureParams& params);

/// Throws InvalidArgument unless `classifier` was trained on FixtureFeatureNames columns and
/// predicts classes among FixtureClassNames, including "none" and one fixture class.
void CheckFixtureClassifier(const ml::Classifier& classifier);

/// Measures one candidate (`members`: indices into `samples`, `shape` from MeasureFixture).
/// attached_share and border are left 0 for the caller.
FixtureEvidence MeasureFixtureEvidence(const FaceSamples& samples,
                                       const std::vector<std::uint32_t>& members,
                                       const Fixture& shape, const PlanarComponent& face,
                                       const RoomFrame& frame, float floor_height,
                                       const FixtureParams& params);

/// The rules' verdict on a candidate: "" for a fixture (its type from `shape_ok` and the shape),
/// else the reason it is none.
const char* FixtureByRules(const FixtureEvidence& evidence, bool shape_ok,
                           const FixtureParams& params);

/// Measures one cluster in front of `face`: centre, footprint length and width, direction,
/// protrusion from the face plane, RANSAC line and circle shares, and the type its shape suggests.
/// Returns false (with the measurements filled) when its shape is neither a handle nor a knob.
bool MeasureFixture(const PointCloud& cloud, const Indices& cluster, const PlanarComponent& face,
                    const RoomFrame& frame, const FixtureParams& params, Fixture& out);

/// Classifies one cluster in front of `face` as a handle or a knob by its shape and its protrusion
/// from the face plane (at least min_protrusion) and measures it; returns false (and leaves `out`
/// unspecified) when it is neither. Exposed for tests.
bool ClassifyFixture(const PointCloud& cloud, const Indices& cluster, const PlanarComponent& face,
                     const RoomFrame& frame, const FixtureParams& params, Fixture& out);

}  // namespace multicue::mapping
