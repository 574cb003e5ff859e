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
    float min_height = 0.012f;         ///< nearest a fixture point lies to its face [m]
    float max_height = 0.10f;          ///< farthest a fixture point lies from its face [m]
    float face_margin = 0.02f;         ///< fixtures may reach this far beyond the face's extent [m]
    float cluster_tolerance = 0.015f;  ///< Euclidean clustering tolerance [m]
    std::size_t min_points = 12;       ///< smaller clusters are noise [points]
    float max_diameter = 0.6f;         ///< larger clusters are too big to grasp [m]
    float max_protrusion_extent = 0.09f;  ///< larger extent along the face normal: no fixture [m]
    float min_handle_length = 0.05f;      ///< a handle is at least this long [m]
    float min_elongation = 2.2f;          ///< length / width of a handle's footprint [-]
    float max_knob_size = 0.09f;          ///< largest extent of a knob [m]
    float line_threshold = 0.008f;        ///< RANSAC line inlier distance [m]
    float circle_threshold = 0.005f;      ///< RANSAC circle inlier distance [m]
    std::uint64_t seed = 1;               ///< RANSAC seed
    /// Throws InvalidArgument naming the first out-of-range field.
    void Validate() const;
};

struct FixtureResult {
    std::vector<Fixture> fixtures;  ///< handles and knobs, ordered by face then position
    std::size_t too_large = 0;      ///< clusters rejected as too big to grasp
    std::size_t unclassified = 0;   ///< neither elongated enough nor small enough
};

/// Fixtures in front of the furniture faces (components labelled kFace) of `structure`.
/// Throws InvalidArgument for bad parameters.
FixtureResult DetectFixtures(const PointCloud& cloud, const RoomFrame& frame,
                             const RoomStructure& structure, const FixtureParams& params = {});

/// Classifies one cluster in front of `face` as a handle or a knob and measures it; returns false
/// (and leaves `out` unspecified) when it is neither. Exposed for tests.
bool ClassifyFixture(const PointCloud& cloud, const Indices& cluster, const PlanarComponent& face,
                     const RoomFrame& frame, const FixtureParams& params, Fixture& out);

}  // namespace multicue::mapping
