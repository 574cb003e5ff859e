#pragma once
/// \file The grid of a furniture face that front_edges.cpp and front_extend.cpp search for the
/// outlines of fronts: per cell face, gap (outline) or unknown. Internal to the mapping module,
/// not part of its API.

#include <cstdint>
#include <vector>

#include <Eigen/Core>

#include "multicue/core/point_cloud.hpp"
#include "multicue/mapping/front_edges.hpp"
#include "multicue/mapping/room_structure.hpp"

namespace multicue::mapping::front_grid_internal {

/// Cell marks of a face's grid.
constexpr std::uint8_t kUnknown = 0, kFaceCell = 1, kGapCell = 2;
/// Cells a fixture hides or makes look like an outline: no evidence either way.
constexpr std::uint8_t kMasked = 3;

/// A face gridded in its plane: per cell unknown, face or gap.
struct OutlineGrid {
    Eigen::Vector2f origin = Eigen::Vector2f::Zero();
    float cell = 0.01f;
    int nu = 0, nv = 0;
    std::vector<std::uint8_t> mark;

    std::uint8_t At(int u, int v) const {
        return u < 0 || v < 0 || u >= nu || v >= nv ? kUnknown
                                                    : mark[static_cast<std::size_t>(v * nu + u)];
    }
    int U(float u) const { return static_cast<int>(std::floor((u - origin.x()) / cell)); }
    int V(float v) const { return static_cast<int>(std::floor((v - origin.y()) / cell)); }
    float UAt(int iu) const { return origin.x() + (static_cast<float>(iu) + 0.5f) * cell; }
    float VAt(int iv) const { return origin.y() + (static_cast<float>(iv) + 0.5f) * cell; }
};

/// The grid of `face` over `points` (cells of params.cell, coarser for huge faces): a cell is gap
/// when it holds an image edge, lies params.recess below the local background, steps
/// params.step in height or params.appearance_step in appearance from a neighbour, or is an
/// empty cell with face cells within params.hole_reach on opposite sides. Fixture points
/// (`is_fixture`) are left out.
OutlineGrid BuildGrid(const PointCloud& cloud, const RoomFrame& frame, const PlanarComponent& face,
                      const Indices& points, const FrontEvidence& ev,
                      const std::vector<std::uint8_t>& is_fixture, const FrontEdgeParams& p);

/// Masks what a fixture hides or shows of itself: the cells of its box grown by `margin`, and
/// the gap and empty cells connected to them within `reach` of the box (its shadow, the colour
/// edges around it), which would otherwise look like an outline next to it.
void MaskFixture(OutlineGrid& g, const Eigen::Vector2f& lo, const Eigen::Vector2f& hi, float margin,
                 float reach);

/// Masks every fixture on face `f` of the grid (MaskFixture with params.margin, reaching
/// params.margin + params.shadow_factor * its protrusion).
void MaskFixtures(OutlineGrid& g, const PointCloud& cloud, const RoomFrame& frame,
                  const PlanarComponent& face, int f, const std::vector<Fixture>& fixtures,
                  const FrontEdgeParams& p);

/// The cells of line `k` (a column when `columns`, else a row) over [a, b], each with the lines
/// either side: how many hold points, how many are gap, the longest run of gap cells (cells
/// without points bridge it), and whether any is masked.
struct LineCount {
    int points = 0, gap = 0, run = 0;
    bool masked = false;
};
LineCount CountLine(const OutlineGrid& g, bool columns, int k, int a, int b);

/// The cells of line `k` alone over [a, b] (no lines either side): how many hold points, how
/// many are gap, how many are masked.
struct OwnLineCount {
    int points = 0, gap = 0, masked = 0;
};
OwnLineCount CountOwnLine(const OutlineGrid& g, bool columns, int k, int a, int b);

/// Whether a counted line of `length` cells is an outline: points along at least `coverage` of
/// it, and at least `support` of its cells with points are gap.
bool IsOutline(const LineCount& n, int length, float coverage, float support);

/// Per component of `s`: the points measured against it (FrontEvidence::point_face, in
/// increasing order), or its own points when the evidence has no faces.
std::vector<Indices> FacePoints(std::size_t num_points, const RoomStructure& s,
                                const FrontEvidence& ev);

/// Searches from line `start` in steps of `dir` (+1 or -1) for a side: along u (columns, over
/// rows [a, b]) when `columns`, else along v (rows, over columns [a, b]). Returns the index of
/// the side's line (or of the last line with points when the face ends first).
int FindSide(const OutlineGrid& g, bool columns, int start, int dir, int a, int b,
             const FrontEdgeParams& p);

/// Like FindSide, but walks at most `max_steps` lines and needs params.extend_support: the index
/// of the gap's own line at the first line that is outline (that line or one of the next two,
/// whichever holds the most gap cells itself), or of the last line with points when the face
/// ends first; -1 when neither happens within max_steps.
int FindSideWithin(const OutlineGrid& g, bool columns, int start, int dir, int a, int b,
                   int max_steps, const FrontEdgeParams& p);

/// Per point of a cloud of `num_points`: 1 where a fixture of `fixtures` holds it (indices out of
/// range are ignored), else 0.
std::vector<std::uint8_t> FixturePoints(std::size_t num_points,
                                        const std::vector<Fixture>& fixtures);

/// Throws InvalidArgument unless every evidence vector is empty or holds `num_points` entries.
void CheckEvidence(const FrontEvidence& ev, std::size_t num_points);

}  // namespace multicue::mapping::front_grid_internal
