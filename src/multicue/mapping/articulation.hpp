#pragma once
/// \file How doors and drawers open (thesis section 4.1.2).
///
/// From one scan, from the fixture: a horizontal handle on a low front is a drawer (prismatic,
/// out of the face) unless the front is taller than any drawer; a horizontal handle near the top
/// of a tall front is a door hinged at its bottom edge (an oven, a dishwasher; a front too narrow
/// for one is hinged at a side; one in a column of drawers, a front directly above or below it
/// and both handles centred, is a deep drawer), near the bottom of a front above the worktop a door
/// hinged at its top edge, and on any other front above the worktop (wall cupboards hold no
/// drawers) a door hinged at the horizontal edge farther from it; a vertical handle (or a knob)
/// near one side edge is a door hinged at the opposite edge. The hinge axis lies in the face plane
/// along that edge, signed so that a positive angle swings the front out of the furniture.
///
/// From two scans of the same view, before and after the robot opened a front: the closed
/// front's points that the opened scan no longer shows are the place it left (when they span a
/// band of a rectangle that covers several drawers, the band is the front), and the points in
/// front of it that were not there before are the moved front. The best plane
/// through them, and the best plane parallel to the closed front, give two hypotheses: a
/// prismatic joint (the parallel plane's distance is the travel) and a revolute joint about the
/// line where the closed front's plane meets a tilted plane (the angle between them is the
/// opening). The hypothesis under which more moved points lie on the front's rectangle, moved
/// that way, wins (a drawer's sides and bottom can outnumber its front in the best plane). A
/// drawer pulled out shows much of its front again; a door seen edge-on, or by little more than
/// its free edge or handle, can make a parallel plane too but covers a strip of the slid
/// rectangle only. A slide covering too little of it becomes a turn, about the tilted plane's
/// axis or, without one, about the edge of the rectangle that the moved points cover best. A
/// tilted plane no moved point of which comes near its axis does not hang there: its turn is
/// taken about the rectangle's edge along that axis; an axis near the front's vertical or
/// horizontal is taken to be that direction. A flap's turn that a drawer's box explains better
/// (moved points beyond the flap's reach and across its plane, or its plane running on behind the
/// face, where a turned front never is) is taken for a slide.

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "multicue/core/point_cloud.hpp"
#include "multicue/mapping/semantic_map.hpp"
#include "multicue/search/kdtree.hpp"

namespace multicue::ml {
class Classifier;
}

namespace multicue::mapping {

struct ArticulationParams {
    float horizontal_handle_deg = 30.0f;  ///< a handle this close to horizontal is horizontal
    /// Two fixtures of a front at most this long, side by side (the line between them within
    /// horizontal_handle_deg of horizontal) and farther apart than its longest handle is long,
    /// are one horizontal handle between them: the two mounts of a long bar found without the
    /// bar, the two knobs of a wide drawer (a door's handle beside a stray fixture is not). 0:
    /// off [m]
    float pair_fixture_max_length = 0.05f;
    float door_min_height = 0.45f;  ///< a front with a horizontal handle this tall is a door [m]
    /// Doors hinged at their bottom edge (ovens, dishwashers: 0.56-0.85 m in the model library)
    /// are at least this wide; a narrower front with a handle near its top is hinged at a
    /// vertical edge [m]
    float flap_min_width = 0.4f;
    /// ... and with the handle at a side edge (side_share), at least this wide: an oven's or a
    /// dishwasher's door may carry its handle off its centre, a cupboard door's handle near its
    /// top corner marks its free edge [m]
    float edge_flap_min_width = 0.55f;
    float top_share = 0.35f;  ///< "near the top": within this share of the height [-]
    /// A horizontal handle whose centre lies within this share of the front's width from a side
    /// edge marks a door hinged at the other side edge (a door's handle sits at its free edge;
    /// flaps carry theirs centred) on a wall cupboard's front (no drawers there) and on a front
    /// at least door_min_height tall (drawers are lower), unless the front is hinged at its
    /// bottom edge (see edge_flap_min_width). Chosen on the tune half; 0: off [-]
    float side_share = 0.2f;
    /// Fronts whose bottom lies above this height are wall cupboards': with a horizontal handle
    /// they are flaps, hinged at the horizontal edge farther from it [m above the floor]
    float flap_min_bottom = 1.2f;
    /// No drawer front is taller: a taller front with a horizontal handle (not near its top) is
    /// a door hinged at the vertical edge farther from the handle [m]
    float drawer_max_height = 0.6f;
    /// Wall cupboards' fronts may be drawers (a horizontal handle away from their bottom and
    /// sides); off, they are doors
    bool wall_drawers = false;
    /// Ovens and dishwashers do not stack, drawers do: a front the fixture rules hinge at its
    /// bottom edge (a horizontal handle near its top), no taller than drawer_max_height, is a
    /// drawer when another front of its column (on its face, overlapping all of its width but
    /// twice this distance, no wider by more) lies directly above or below it (gap within this
    /// distance), both with a handle centred on the front's middle
    /// (stack_centre_share); 0: off. Used by the overload that sees all of a map's fronts [m]
    float stack_tolerance = 0.04f;
    /// A drawer's handle is centred across it: within this share of the front's width of its
    /// middle. A door under a row of drawers may carry a handle running across at its free edge,
    /// which a deep drawer's does not [-]
    float stack_centre_share = 0.05f;
    float revolute_upper = 1.5708f;  ///< upper limit given to revolute fronts from one scan [rad]
    float prismatic_upper = 0.4f;    ///< upper limit given to drawers from one scan [m]
    /// A hinge lies this far behind the front's surface (the door's thickness to its hinge
    /// line): the median over the revolute fronts of simulated kitchens of the tune half, 1.9-2.0
    /// cm on either fold for the Kinect, 1.2-1.9 cm for the laser [m]
    float hinge_depth = 0.019f;
    /// HingeEdgeSeen: the front's points within this of its point nearest the hinge edge show
    /// that edge, and the view is checked this far beyond it [m].
    float edge_band = 0.03f;
    /// HingeEdgeSeen: points this close to an organized scan's image border lie at the border
    /// of the view [pixels].
    int edge_border = 2;
    /// Throws InvalidArgument naming the first out-of-range field.
    void Validate() const;
};

/// The articulation of `front` from its fixtures' orientation and place: its longest handle's,
/// or one horizontal handle between two small fixtures side by side
/// (ArticulationParams::pair_fixture_max_length). `floor_height` (NaN if unknown) is along frame
/// up. Fronts without fixtures get JointType::kUnknown.
Articulation ArticulationFromFixtures(const Front& front, const std::vector<Fixture>& fixtures,
                                      const RoomFrame& frame, float floor_height,
                                      const ArticulationParams& params = {});
/// The same for `fronts[index]`, with the other fronts around it: a front in a stack of drawers
/// is a drawer, not a flap (see ArticulationParams::stack_tolerance).
Articulation ArticulationFromFixtures(const std::vector<Front>& fronts, std::size_t index,
                                      const std::vector<Fixture>& fixtures, const RoomFrame& frame,
                                      float floor_height, const ArticulationParams& params = {});

/// Learned one-scan joints (`MapKitchen`'s joint classifier, `multicue train joints`): instead of
/// the fixture rules above, a classifier trained on simulated kitchens names each front's joint:
/// "prismatic", "revolute_side" (hinged at the vertical edge farther from its main fixture),
/// "revolute_bottom" or "revolute_top" (a flap hinged at that edge).
const std::vector<std::string>& JointClassNames();

/// The columns of JointFeatures.
const std::vector<std::string>& JointFeatureNames();

/// What the joint classifier sees of front `front` of `map`: its rectangle's width, height and
/// aspect, its bottom and top above the floor (map.floor_height; 0 when unknown), its fixtures'
/// count and its main fixture's direction (horizontal within params.horizontal_handle_deg),
/// length (also as a share of the front's extent along it), place on the front (0..1 across and
/// up, and off the middle across), kind and protrusion, the fronts directly above and below it
/// on its face (overlapping 60 % of its width, within 6 cm), its furniture piece (the other
/// fronts, width and height; zeros without a piece), and the class of its present joint (the
/// fixture rules' answer, one-hot; zeros without a joint). Throws std::out_of_range for a bad
/// index.
std::vector<float> JointFeatures(const KitchenMap& map, std::size_t front,
                                 const ArticulationParams& params = {});

/// The class (JointClassNames) of a joint of `type` along `axis` through `point` on front `f`;
/// "" for JointType::kUnknown.
std::string JointClassOf(JointType type, const Eigen::Vector3f& axis, const Eigen::Vector3f& point,
                         const Front& f, const RoomFrame& frame);

/// Throws InvalidArgument unless `classifier` is trained, on JointFeatureNames, with classes of
/// JointClassNames only.
void CheckJointClassifier(const ml::Classifier& classifier);

/// Replaces the joint of every front of `map` whose articulation came from its fixture (source
/// "fixture") by the one `classifier` names, hinged as the class says, with the limits of
/// `params`; hinge_seen is left for the caller to recompute. Returns the indices of the fronts
/// whose joint changed. The map's furniture pieces are read (JointFeatures), so group them first.
/// Throws as CheckJointClassifier.
std::vector<std::size_t> ClassifyJoints(KitchenMap& map, const ml::Classifier& classifier,
                                        const ArticulationParams& params = {});

/// Whether `scans` saw the edge that revolute front `front`'s hinge lies on (true for other
/// joints). `front` indexes the scans merged in order, scan k starting at `scan_offsets[k]`.
/// A scan says so from the front's points nearest that edge (within `edge_band`): an organized
/// scan saw the edge unless such points lie at its image border (`edge_border`) along most of
/// the stretch of the edge where it has them (steps of `edge_band`); an unorganized
/// one with a sensor position, if its rays reached the place `edge_band` beyond the edge, or
/// went past it, along most of the edge (out of the field of view, or hidden by something
/// nearer, it did not). One scan that saw it is enough; true when no scan can tell.
bool HingeEdgeSeen(const Front& front, const std::vector<PointCloud>& scans,
                   const std::vector<std::size_t>& scan_offsets,
                   const ArticulationParams& params = {});

struct MotionParams {
    float change_distance = 0.02f;  ///< opened-scan points this far from every closed-scan point
                                    ///< are new [m]
    float min_offset = 0.02f;       ///< new points at least this far in front of the face [m]
    /// How far a drawer may run out of its front [m]; a turning front reaches no farther from it
    /// than its own size.
    float reach = 1.2f;
    /// A turn brings no part of the front farther out of the face than the rectangle's farthest
    /// corner from the hinge; moved points straight out of the rectangle beyond that by more than
    /// this margin are no part of the turned front [m]
    float turn_reach_margin = 0.05f;
    /// When the turn taken is a flap's (about a horizontal axis) and at least this share of the
    /// moved points straight out of the front's rectangle (and `min_points` of them) lie beyond
    /// its reach, with at least `min_beyond_off_plane` of those off the turned front's plane,
    /// the front slid instead: a drawer pulled out so far that only its box is seen, whose bottom
    /// the turn explains as a flap opened downwards and whose sides stand across that plane. A
    /// flap found shorter than it is reaches beyond its rectangle too, but on its own plane;
    /// side doors are never changed (their reach is the rectangle's width, which a front found
    /// with its neighbour gets wrong). Chosen on simulated kitchens of the tune half: 0.05-0.2
    /// turned two drawers right (share 0.22) and, without the plane test, one flap wrong (share
    /// 0.35, none of it off the flap's plane; the drawers' 0.8 off it); 0: off [-]
    float max_beyond_turn_share = 0.15f;
    /// See max_beyond_turn_share: a flap's own points lie on its plane, up to noise; a quarter
    /// (0.1-0.75 scored alike on the tune half) [-]
    float min_beyond_off_plane = 0.25f;
    /// A turned front ends at its hinge, in front of the face; a drawer's box runs on behind it.
    /// When the turn taken is a flap's, hinged below the front's middle, and the new points
    /// behind the face, within the front's outline, on the turned front's plane extended number
    /// at least this share of the moved points on that plane out of the face (and `min_points`),
    /// the front slid instead: a deep drawer pulled out, its front out of view, whose bottom
    /// passes for a flap opened downwards. Chosen on simulated kitchens of the tune half, where
    /// such drawers showed 0.21-2.3 points behind per point out and flaps hinged low (ovens,
    /// dishwashers) at most 0.24, but for one dishwasher door seen mostly out of view (1.28); 0.5
    /// turned four drawers right and that door wrong. 0: off [-]
    float min_through_share = 0.5f;
    /// A front the map already holds for a drawer (its fixture, one scan) is taken for a turn
    /// only when the turn's plane covers at least this share of the cells the opened scan could
    /// see (of all cells without a sensor position); else it slid. A deep drawer pulled out
    /// towards the sensor may leave the view with its front, and what is seen of its box then
    /// passes for a door turned a little. Chosen on simulated kitchens of the tune half (2001
    /// pairs, both sensors): 0.44-0.5 turned five drawers right and one door wrong, 0.55 a
    /// second door (a mini fridge's, at 0.51), 0.7 as many doors as drawers. 0: off [-]
    float min_turn_coverage_for_drawer = 0.5f;
    float plane_threshold = 0.015f;  ///< RANSAC plane inlier distance for the moved front [m]
    std::size_t min_points = 40;     ///< fewer moved points: no motion seen [points]
    float parallel_deg = 8.0f;       ///< planes closer than this: prismatic [deg]
    /// A slide that covers less than this share of the front's rectangle moved out (cells of
    /// `coverage_cell`) is taken for a turn, where the opened scan has no sensor position or
    /// `seen_coverage` is off; 0: the two planes' support alone decides. Chosen on
    /// simulated kitchens of the tune half (0.25-0.35 scored alike; from 0.4 drawers fail) [-]
    float min_slide_coverage = 0.3f;
    /// The same among the cells the opened scan could see (`seen_coverage`). Chosen on simulated
    /// kitchens of the tune half, both sensors (0.3 lost doors, 0.5 drawers) [-]
    float min_seen_slide_coverage = 0.4f;
    float coverage_cell = 0.03f;  ///< cell of the coverage grid on the front [m]
    /// With a sensor position in the opened scan, the coverages count only the cells the scan
    /// could see where the hypothesis puts them (the ray from the sensor reached them), and the
    /// hypothesis covering the larger share wins; off, or without a sensor position, the cells
    /// of the whole rectangle count and the one with more moved points on the front wins.
    bool seen_coverage = true;
    /// The map's furniture is aligned with the room's axes, and so are its hinges: a hinge axis
    /// found from the tilted plane within this angle of the front's vertical or of its
    /// horizontal in-plane direction is taken to be that direction (the plane fit's tilt is
    /// noise); 0 keeps the fitted direction [deg]
    float axis_snap_deg = 10.0f;
    /// A hinge from the tilted plane that no moved point on the plane comes within this of is
    /// not believed (a door hangs on its hinge); the turn about the front's edge along that axis
    /// that the moved points cover best is taken instead; 0: always believed. Chosen on the
    /// simulated kitchens of the tune half, where 96 % of the hinges this far from their door
    /// were more than 0.3 m off and 2 % of the others [m]
    float max_hinge_gap = 0.15f;
    /// A front's rectangle may span several drawers (their fixtures missed, one rectangle found
    /// from the outlines), of which one moved. The band of it whose closed-scan points the
    /// opened scan no longer shows (their 2 % to 98 % quantiles along the front's vertical,
    /// grown by `change_distance`, the margin within which they were not counted; across the
    /// whole width, as drawers stack) is taken for the front when it is less than this share of
    /// the rectangle's height; 0: the rectangle as it is [-]
    float vacated_max_share = 0.8f;
    /// UpdateArticulationFromOpenedScan takes for the opened front the one that lost the most
    /// of its own points (`MotionResult::vacated_points`); off: the one with the most moved
    /// points
    bool select_by_vacated = true;
    std::uint64_t seed = 1;
    /// Throws InvalidArgument naming the first out-of-range field.
    void Validate() const;
};

struct MotionResult {
    bool found = false;         ///< enough moved points on a plane
    Articulation articulation;  ///< source "motion"; limits [0, observed opening]
    float opening = 0.0f;       ///< observed angle [rad] or distance [m]
    std::size_t moved_points = 0;
    Indices moved;  ///< indices into `opened` of the moved front's points
    /// Shares of the front's rectangle covered by moved points when slid out by the parallel
    /// plane's travel and when turned by the tilted plane's hinge (-1: no such hypothesis or not
    /// computed).
    float slide_coverage = -1.0f, turn_coverage = -1.0f;
    /// The parallel plane's distance in front of the face [m] (-1: no such plane), and the moved
    /// points that lie on the front's rectangle when slid back by it or turned back about the
    /// tilted plane's hinge.
    float slide_travel = -1.0f;
    std::size_t slide_points = 0, turn_points = 0;
    /// slide_coverage and turn_coverage among the cells the opened scan could see (the ray from
    /// its sensor reached the cell's centre, placed as the hypothesis places it); -1: not known
    /// (no sensor position).
    float slide_seen_coverage = -1.0f, turn_seen_coverage = -1.0f;
    /// The rectangle (face coordinates, as Front::min / max) the joint was found for: the
    /// front's, or the band of it that the motion vacated (see `vacated_max_share`).
    Eigen::Vector2f front_min = Eigen::Vector2f::Zero(), front_max = Eigen::Vector2f::Zero();
    /// Closed-scan points on the front's rectangle with no opened-scan point within
    /// `change_distance`: the place the front left (or its motion hides).
    std::size_t vacated_points = 0;
    /// Moved points straight out of the front's rectangle (within its outline, 5 cm margin),
    /// and of them those farther out of the face than the turn taken can bring any part of the
    /// rectangle (its farthest corner from the hinge axis) by more than `turn_reach_margin`: a
    /// drawer's box, seen where its front is not (beyond_turn_points 0 when no turn was taken).
    std::size_t outline_points = 0, beyond_turn_points = 0;
    /// Of beyond_turn_points, those off the turned front's plane (by twice `plane_threshold`).
    std::size_t beyond_off_plane = 0;
    /// How far the turned rectangle reaches out of the face (-1: no turn taken) [m].
    float turn_reach = -1.0f;
    /// Whether the turn taken is a flap's: about an axis along the front's horizontal.
    bool turn_flap = false;
    /// With a turn taken: the moved points on the turned front's plane (out of the face), and
    /// the new points behind the face, within the front's outline, on that plane extended.
    std::size_t turned_points = 0, through_points = 0;
};

/// The joint of `front` from a scan `closed` in which it is shut and a scan `opened` taken from
/// the same place after it was opened (both in the same frame). The joint the front holds before
/// counts where it is a drawer and the turn found is weakly seen (`min_turn_coverage_for_drawer`).
/// Throws InvalidArgument for bad parameters; empty clouds give found = false.
MotionResult ArticulationFromMotion(const PointCloud& closed, const PointCloud& opened,
                                    const Front& front, const MotionParams& params = {});
/// The same with a k-d tree over the closed scan built once (for trying many fronts).
MotionResult ArticulationFromMotion(const KdTree& closed, const PointCloud& opened,
                                    const Front& front, const MotionParams& params = {});

/// The front that moved between the map's cloud `closed` and a scan `opened` of the same scene
/// with one front opened: of the fronts where ArticulationFromMotion finds a motion, the one
/// that lost the most of its own points (`vacated_points`; ties: the most moved points; see
/// `select_by_vacated`). Its articulation is replaced by ArticulationFromMotion's. When only a
/// band of its rectangle moved (`MotionResult::front_min` / `front_max`), the front is cut down
/// to that band, and the rest below and above it (strips at least two coverage cells tall) are
/// appended as fronts of their own, with the points and fixtures on them (one with a fixture
/// hinged by ArticulationFromFixtures, its `hinge_seen` from `closed`); group and type the
/// furniture again afterwards. Returns the front's index, or -1 when no front moved. `map` must
/// have been built from `closed`: a front's point outside it throws InvalidArgument, before any
/// change.
int UpdateArticulationFromOpenedScan(KitchenMap& map, const PointCloud& closed,
                                     const PointCloud& opened, const MotionParams& params = {});

}  // namespace multicue::mapping
