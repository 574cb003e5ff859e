#pragma once
/// \file Fixtures of furniture faces (thesis section 4.1.2): the points in the polygonal prism in
/// front of each face that lie on no axis-aligned plane are clustered by Euclidean distance;
/// clusters too big to grasp are rejected, and RANSAC line and circle fits, with the footprint's
/// elongation, tell handles (long, on a line) from knobs (compact, round).

#include <cstddef>
#include <cstdint>
#include <vector>

#include "multicue/core/point_cloud.hpp"
#include "multicue/mapping/room_structure.hpp"
#include "multicue/mapping/semantic_map.hpp"

namespace multicue::mapping {

struct FixtureParams {
    float min_height = 0.012f;  ///< nearest a fixture point lies to its face [m]
    float max_height = 0.10f;   ///< farthest a fixture point lies from its face [m]
    /// Points on a plane parallel to the face (a handle's bar seen head-on, noise of the face)
    /// must stand out by aligned_noise * r^2 at range r, at least by min_height [1/m]
    float aligned_noise = 0.0f;
    float face_margin = 0.02f;         ///< fixtures may reach this far beyond the face's extent [m]
    float cluster_tolerance = 0.015f;  ///< Euclidean clustering tolerance [m]
    float merge_gap = 0.025f;          ///< clusters whose boxes lie closer are one fixture [m]
    std::size_t min_points = 12;       ///< smaller clusters are noise [points]
    float max_diameter = 0.6f;         ///< larger clusters are too big to grasp [m]
    float max_protrusion_extent = 0.09f;  ///< larger extent along the face normal: no fixture [m]
    float min_protrusion = 0.029f;  ///< a fixture reaches at least this far out of its face [m]
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
    /// Throws InvalidArgument naming the first out-of-range field.
    void Validate() const;
};

/// A cluster in front of a face that did not become a fixture, and why.
struct RejectedCluster {
    Eigen::Vector3f center = Eigen::Vector3f::Zero();  ///< of its bounding box [m]
    std::size_t points = 0;
    /// "too large", "image border", "shape", "not in front of the face", "attached to another
    /// plane"
    const char* reason = "";
};

struct FixtureResult {
    std::vector<Fixture> fixtures;          ///< handles and knobs, ordered by face then position
    std::vector<RejectedCluster> rejected;  ///< the clusters dropped
    std::size_t too_large = 0;              ///< clusters rejected as too big to grasp
    std::size_t unclassified = 0;           ///< rejected for any other reason
};

/// Fixtures in front of the furniture faces (components labelled kFace) of `structure`.
/// `ranges` holds each point's distance to its sensor (empty: to cloud.sensor_origin).
/// Throws InvalidArgument for bad parameters or ranges of the wrong size.
FixtureResult DetectFixtures(const PointCloud& cloud, const RoomFrame& frame,
                             const RoomStructure& structure, const FixtureParams& params = {},
                             const std::vector<float>& ranges = {});

/// Classifies one cluster in front of `face` as a handle or a knob and measures it; returns false
/// (and leaves `out` unspecified) when it is neither. Exposed for tests.
bool ClassifyFixture(const PointCloud& cloud, const Indices& cluster, const PlanarComponent& face,
                     const RoomFrame& frame, const FixtureParams& params, Fixture& out);

}  // namespace multicue::mapping
