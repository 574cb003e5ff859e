#pragma once
/// \file Door and drawer fronts grown from fixtures (thesis section 4.1.2, Figure 4.4): points of
/// the face around a fixture's footprint seed a model of the front's appearance, the median and
/// the MAD (median absolute deviation) of its colour or intensity; the region grows over
/// neighbouring face points within alpha = 2 MAD of the median, the model is re-estimated from the
/// region, and growing repeats until median and MAD are stable. Regions of different fixtures that
/// overlap are marked and split between them (at the outline between two fixtures where the
/// outline evidence shows one, else each point to the nearest fixture), and every front gets a
/// rectangular approximation on the face plane.

#include <cstddef>
#include <utility>
#include <vector>

#include "multicue/core/point_cloud.hpp"
#include "multicue/mapping/front_edges.hpp"
#include "multicue/mapping/room_structure.hpp"
#include "multicue/mapping/semantic_map.hpp"

namespace multicue::mapping {

/// What the region growing compares.
enum class AppearanceCue {
    kAuto,       ///< colour when the cloud has colours, else intensity, else none
    kColor,      ///< grey level of the RGB colour [0, 255]
    kIntensity,  ///< intensity times intensity_scale
    /// No appearance (a depth camera without colour, a laser without intensity): every point
    /// looks the same, so a region grows by its offset from the face alone and ends where the
    /// outlines (FrontEvidence) part it from its neighbours
    kNone,
};

struct FrontParams {
    AppearanceCue cue = AppearanceCue::kAuto;
    float intensity_scale = 255.0f;  ///< intensity -> appearance units [-]
    float seed_min = 0.01f;  ///< seeds lie at least this far from the fixture's footprint [m]
    float seed_max = 0.05f;  ///< and at most this far (the search radius) [m]
    /// The face is gridded into cells of this size in its plane; the region grows over cells
    /// holding the mean appearance and offset of their points [m]
    float cell_size = 0.015f;
    float alpha_mads = 2.0f;  ///< alpha = alpha_mads * MAD (the thesis' 2 MAD) [-]
    float min_alpha = 40.0f;  ///< alpha is at least this [appearance units]
    /// Neighbours joined in one step differ by at most this : the region stops
    /// at the edges around a front even where light makes the front's colour drift
    /// [appearance units]
    float local_alpha = 3.0f;
    /// The model also holds the points' offset from the face plane (median and MAD): a door
    /// standing out of its frame ends where the offset changes. The offset's alpha is
    /// alpha_mads * its MAD, at least this [m]
    float min_offset_alpha = 0.03f;
    int max_rounds = 8;             ///< model re-estimations at most [rounds]
    float stable_change = 0.5f;     ///< stable when median and MAD move less [appearance units]
    std::size_t min_points = 30;    ///< smaller regions are no fronts [points]
    float overlap_share = 0.1f;     ///< regions sharing this share of the smaller overlap [-]
    float rect_percentile = 0.01f;  ///< rectangle from these lower/upper quantiles of u, v [-]
    /// A front's points become the face points inside its rectangle when its region fills at
    /// least min_fill of them (shadows and noise left holes); otherwise the region stays
    bool fill_rectangle = true;
    float min_fill = 0.6f;  ///< [-]
    /// Points no planar component explains (range noise off the face's plane, normals bent at
    /// a door's edge) join the front whose rectangle holds them, or lies nearest within
    /// claim_margin, when they lie at most claim_front out of its face and claim_behind behind
    /// it (ClaimUnexplainedPoints); claim_front 0: off. Chosen on simulated kitchens of the tune
    /// half (3 cm and 5 cm out and behind scored alike, 2 cm lower; margins of 4-8 cm alike,
    /// 2 cm and none lower) [m]
    float claim_front = 0.03f;
    float claim_behind = 0.03f;  ///< [m]
    float claim_margin = 0.04f;  ///< [m]
    /// Overlapping regions of two fixtures side by side (or one above the other) are split at
    /// the line between them that is outline (FrontEvidence, as ExtendFrontsToOutlines reads
    /// it) in the largest share of its cells with points, when that share reaches
    /// split_support; otherwise, or without evidence, each point goes to the nearest fixture
    /// (with several lines, the nearest of those on whose side of all their lines it lies).
    /// Handles sit near a front's free edge, so halfway between two fixtures is rarely where
    /// one front ends. Off: always the nearest fixture
    bool split_at_outlines = true;
    /// Chosen on simulated kitchens of the tune half (0.3 and 0.5 scored alike, 0.7 lower) [-]
    float split_support = 0.5f;
    /// Two fixtures whose overlapping regions no outline parts, each within this of its own end
    /// of their common region (along the axis that parts them), are one front's: the two knobs
    /// of a wide drawer, the handle and button of a dishwasher. Doors side by side carry their
    /// handles at their free edges, which meet in the middle, or both on the same side. Where
    /// more than two regions overlap, only two side by side in one row, at most 2 seed_max tall
    /// and half their front's width apart (the mounts of a drawer's long bar); 0: off (split as
    /// above) [m]
    float pair_end_reach = 0.15f;
    /// ... as long as that region is no wider than this (one front) [m]
    float pair_max_width = 1.2f;
    /// Fronts do not nest: a front whose rectangle lies within a larger one's in at least this
    /// share of its area, on a parallel face up to nest_depth in front of or behind that one's,
    /// is part of the larger one (MergeNestedFronts). A frame-and-panel door grows one front
    /// over its frame from its handle and another over its recessed panel, a plane of its own;
    /// a door's window does the same. A front inside another on the same face is left alone:
    /// there the larger one is the one in error, a region run on over its neighbours. Above 1:
    /// off [-]
    float nest_share = 0.8f;
    float nest_depth = 0.05f;  ///< [m]
    /// Throws InvalidArgument naming the first out-of-range field.
    void Validate() const;
};

/// Fronts for the fixtures (indices into `fixtures` kept in Front::fixtures). Knobs that belong to
/// a row of three or more knobs (a control panel) grow no front of their own. With `evidence`
/// (and the outline grid's parameters `outline`), overlapping regions are split at the outlines
/// between their fixtures (FrontParams::split_support).
/// Throws InvalidArgument for bad parameters or evidence of the wrong size, DataError when the
/// cue needs colours or intensity the cloud lacks.
std::vector<Front> SegmentFronts(const PointCloud& cloud, const RoomFrame& frame,
                                 const RoomStructure& structure,
                                 const std::vector<Fixture>& fixtures,
                                 const FrontParams& params = {},
                                 const FrontEvidence* evidence = nullptr,
                                 const FrontEdgeParams& outline = {});

/// Merges every front nested in a larger one on a parallel face just in front of or behind it
/// (FrontParams::nest_share, nest_depth) into the smallest front holding it: its points join
/// that front, whose rectangle, face and fixtures stay (the nested front's fixtures, on a
/// panel's edge or a window's frame, are no longer any front's). Fronts are compared in the order
/// of their rectangles' areas, so the result does not depend on their order. Throws InvalidArgument
/// for bad parameters or a front on no face of `structure`.
void MergeNestedFronts(const RoomStructure& structure, std::vector<Front>& fronts,
                       const FrontParams& params = {});

/// Points of `cloud` that no component of `structure` explains (point_component -1) and no
/// fixture holds join the front whose rectangle holds them (the smallest, where rectangles
/// overlap; else the front whose rectangle lies nearest, within params.claim_margin), when they
/// lie at most params.claim_front out of its face's plane and params.claim_behind behind it: the
/// rectangle stands for the front (thesis section 4.1.2), and range noise carries some of a
/// door's points off its plane. Off when claim_front is 0. Throws InvalidArgument for bad
/// parameters or a front on no face of `structure`.
void ClaimUnexplainedPoints(const PointCloud& cloud, const RoomFrame& frame,
                            const RoomStructure& structure, const std::vector<Fixture>& fixtures,
                            std::vector<Front>& fronts, const FrontParams& params = {});

/// The rectangle of `points` on `face`: the `quantile` and 1 - `quantile` quantiles of their face
/// coordinates u and v (lower corner, upper corner). `points` must not be empty.
std::pair<Eigen::Vector2f, Eigen::Vector2f> PointsRectangle(const PointCloud& cloud,
                                                            const RoomFrame& frame,
                                                            const PlanarComponent& face,
                                                            const Indices& points, float quantile);

/// Gives `front` the rectangle [lo, hi] on `face` (face coordinates): its corners, the face's
/// axes and normal, and the rectangle's centre in the world.
void SetFrontRectangle(Front& front, const PlanarComponent& face, const RoomFrame& frame,
                       const Eigen::Vector2f& lo, const Eigen::Vector2f& hi);

/// Per fixture: true for a knob in a row of at least three knobs on one face (a control panel),
/// which opens nothing on its own.
std::vector<bool> PanelKnobs(const std::vector<Fixture>& fixtures);

/// The appearance value of every point for a cue (NaN where undefined). Exposed for tests.
std::vector<float> AppearanceValues(const PointCloud& cloud, AppearanceCue cue,
                                    float intensity_scale);

}  // namespace multicue::mapping
