#pragma once
/// \file Door and drawer fronts as rectangles between their outlines (thesis section 4.1.2; the
/// gaps between cupboard doors of Marton et al. 2008). A front's outline is a gap: a line of
/// colour or intensity edges in the camera image, of points lying below the face's local
/// background, of height steps, or of missing points between points of the face. The face is
/// gridded in its plane and every cell marked as outline or not; from each fixture the search
/// walks outwards, left, right, down and up, until a line of cells parallel to that side is
/// mostly outline (or the face ends), and the four lines bound the front. Fronts are axis-aligned
/// rectangles on axis-aligned faces, so each side is one column or row of cells: evidence is
/// summed along its whole length, and a thin, faint gap that no single point shows is found.

#include <cstdint>
#include <vector>

#include "multicue/core/point_cloud.hpp"
#include "multicue/mapping/room_structure.hpp"
#include "multicue/mapping/semantic_map.hpp"

namespace multicue::mapping {

struct ImageEdgeParams {
    float low = 20.0f;   ///< Canny hysteresis thresholds on the grey image [grey levels]
    float high = 50.0f;  ///< [grey levels]
    /// Intensity images are stretched from this lower to the upper quantile onto 0 .. 255 [-]
    float stretch_quantile = 0.02f;
    /// Throws InvalidArgument naming the first out-of-range field.
    void Validate() const;
};

/// Per point of an organized scan: 1 where its grey image (colour, else intensity) has a Canny
/// edge, 0 elsewhere; all 0 for unorganized scans or scans without colour and intensity. Invalid
/// pixels are black, so the outline of a gap the sensor could not see is an edge too.
std::vector<std::uint8_t> ImageEdges(const PointCloud& scan, const ImageEdgeParams& params = {});

struct FrontEdgeParams {
    float cell = 0.01f;     ///< grid cell in the face plane [m]
    float recess = 0.006f;  ///< cells this far below the local background are gap [m]
    float step = 0.012f;    ///< neighbouring cells whose heights differ this much are gap [m]
    int hole_reach = 3;     ///< empty cells with face cells this near on both sides are gap [cells]
    /// Neighbouring cells whose mean appearance (FrontEvidence::appearance) differs this much
    /// are gap [grey levels or scaled intensity]
    float appearance_step = 25.0f;
    /// A side is found where the cells along it (one cell either side) are gap in this share of
    /// the rows or columns that hold points [-]
    float min_support = 0.45f;
    float min_coverage = 0.3f;  ///< ... and points cover this share of its length [-]
    float margin = 0.02f;       ///< sides lie at least this far beyond the fixture [m]
    /// Gap and empty cells connected to a fixture within margin + shadow_factor * its protrusion
    /// are its shadow and edges, no outline [-]
    float shadow_factor = 2.0f;
    float start_reach = 0.06f;  ///< first search: the fixture's extent grown by this [m]
    int rounds = 3;             ///< alternating searches of the sides [rounds]
    float face_end = 0.05f;     ///< this much without points ends the face [m]
    float min_size = 0.08f;     ///< narrower or lower fronts are dropped [m]
    /// Rectangles of two fixtures overlapping this much (IoU) are one front [-]
    float same_front_iou = 0.6f;
    std::size_t min_points = 30;  ///< fronts with fewer points are dropped [points]
    /// ExtendFrontsToOutlines: a side moves at most this far out to reach its outline [m]
    float max_extend = 0.3f;
    /// ExtendFrontsToOutlines: a side's line is outline in this share of the rows or columns
    /// that hold points (a stricter min_support: a grown front already ends near its outline) [-]
    float extend_support = 1.0f;
    /// Throws InvalidArgument naming the first out-of-range field.
    void Validate() const;
};

/// What the outline search reads per point of the mapped cloud (each vector empty or one entry
/// per point): the face the point was measured against and its height above that face's local
/// background (FixtureResult::point_face and point_residual), its image edge flag, and its
/// appearance where no image edges are known.
struct FrontEvidence {
    std::vector<std::int32_t> point_face;
    std::vector<float> point_residual;
    std::vector<std::uint8_t> image_edge;
    /// Grey level or scaled intensity of points whose scan gives no image edges (unorganized
    /// scans); NaN elsewhere.
    std::vector<float> appearance;
};

/// The fronts of the fixtures on the faces of `structure`: one rectangle per fixture (fixtures
/// whose rectangles coincide share one front), the face's points inside it (fixture points
/// excluded; a point inside two rectangles goes to the nearer fixture). Knobs in a row of three
/// or more (a control panel) open nothing. Throws InvalidArgument for bad parameters or evidence
/// of the wrong size.
std::vector<Front> FrontsFromEdges(const PointCloud& cloud, const RoomFrame& frame,
                                   const RoomStructure& structure,
                                   const std::vector<Fixture>& fixtures,
                                   const FrontEvidence& evidence,
                                   const FrontEdgeParams& params = {});

/// Grows the rectangle of each front (say, grown by SegmentFronts, which stops where the front's
/// colour drifts) side by side outwards to its outline, at most params.max_extend, never into
/// another front's rectangle; the face points in the grown part that belong to no front join it.
/// A side already on an outline stays. Throws InvalidArgument for bad parameters or evidence of
/// the wrong size.
void ExtendFrontsToOutlines(const PointCloud& cloud, const RoomFrame& frame,
                            const RoomStructure& structure, const std::vector<Fixture>& fixtures,
                            const FrontEvidence& evidence, std::vector<Front>& fronts,
                            const FrontEdgeParams& params = {});

/// Fronts whose fixture was not found (AddFrontsFromGaps): the rest of a furniture face is cut
/// along its outlines into rectangles, and the rectangles of a front's size become fronts
/// without fixtures or complete the front of the fixture they hold.
struct GapFrontParams {
    bool enabled = true;
    /// A cut is a column or row of cells (one cell either side) that is outline in this share of
    /// the cells along it that hold points [-]
    float cut_support = 0.6f;
    float cut_coverage = 0.5f;  ///< ... and whose cells hold points along this share of it [-]
    /// ... and whose longest unbroken run of outline cells spans this share of its cells with
    /// points: the gap between two fronts runs along their whole edge, while noise, texture and
    /// shading scatter outline cells over a front [-]
    float cut_run = 0.4f;
    /// No cut lies closer than this to a side of the rectangle it cuts: near a front's edge,
    /// shading and texture look like outlines too, so a narrow frame around the doors stays
    /// with them [m]
    float cut_margin = 0.2f;
    float min_size = 0.2f;    ///< rectangles narrower or lower are no front [m]
    float max_width = 1.2f;   ///< wider rectangles are no front [m]
    float max_height = 2.2f;  ///< higher rectangles are no front [m]
    /// A rectangle's cells hold points in at least this share (a front is seen whole) [-]
    float min_fill = 0.5f;
    /// Rectangles sharing this share of their area with a front of a fixture are that front [-]
    float max_taken = 0.2f;
    std::size_t min_points = 50;  ///< rectangles with fewer free face points are dropped
    int max_depth = 12;           ///< cuts nested at most this deep [-]
    /// The front of a fixture also takes the free face points of the rectangle that holds its
    /// fixtures (and no other front's), as long as it stays within max_width and max_height;
    /// a side of the front that is outline along its whole line (FrontEdgeParams::
    /// extend_support) stays where it is
    bool grow_fixture_fronts = true;
    /// A front of a fixture that the same cuts part (searched within its rectangle, no closer
    /// than cut_margin to its sides) keeps the rectangle holding its fixtures; its points in the
    /// others are free for fronts without fixtures. A region grown from a handle runs on over a
    /// gap of the front's own colour into the next door, whose handle was missed
    bool split_fixture_fronts = false;
    /// Throws InvalidArgument naming the first out-of-range field.
    void Validate() const;
};

/// Adds a front without fixtures for every part of a furniture face that its outlines bound as a
/// front-sized rectangle outside the fronts already found: the face is gridded as for
/// ExtendFrontsToOutlines (`grid`), cut recursively at its strongest outline line (a guillotine
/// partition: doors side by side, drawers stacked), and each leaf rectangle that holds enough
/// free face points, is filled, of a front's size and not on a front already found, becomes a
/// front of those points (no fixtures, so its joint stays unknown until a scan shows it open).
/// With params.grow_fixture_fronts, a leaf holding the fixtures of one front found already
/// gives that front its free points instead (the front's rectangle grows to cover them).
/// Throws InvalidArgument for bad parameters or evidence of the wrong size.
void AddFrontsFromGaps(const PointCloud& cloud, const RoomFrame& frame,
                       const RoomStructure& structure, const std::vector<Fixture>& fixtures,
                       const FrontEvidence& evidence, std::vector<Front>& fronts,
                       const FrontEdgeParams& grid = {}, const GapFrontParams& params = {});

}  // namespace multicue::mapping
