#pragma once
/// \file The kitchen mapping pipeline (thesis section 4.1, Figure 4.1): scans in one frame ->
/// normals -> room axes -> room structure -> fixtures -> fronts -> articulation -> furniture and
/// container types. Each stage is a public function of its own header; MapKitchen only runs them
/// in order and labels the points.

#include <cstddef>
#include <string>
#include <utility>
#include <vector>

#include "multicue/core/point_cloud.hpp"
#include "multicue/mapping/articulation.hpp"
#include "multicue/mapping/containers.hpp"
#include "multicue/mapping/fixtures.hpp"
#include "multicue/mapping/front_edges.hpp"
#include "multicue/mapping/fronts.hpp"
#include "multicue/mapping/room_axes.hpp"
#include "multicue/mapping/room_structure.hpp"
#include "multicue/mapping/semantic_map.hpp"
#include "multicue/ml/classifier.hpp"

namespace multicue::mapping {

/// The sensor the parameters are made for.
enum class KitchenSensor {
    kKinect,  ///< dense RGB-D frames, millimetre noise near, colour
    kLaser,   ///< tilting laser sweeps, centimetre noise, intensity
};

/// How fronts are segmented.
enum class FrontSegmentation {
    kOutline,        ///< rectangles between the fronts' outlines (front_edges.hpp)
    kRegionGrowing,  ///< colour region growing from the fixtures (fronts.hpp)
};

struct MapKitchenParams {
    /// Organized scans: image-space normals with this half window [pixels]; others: k-d tree
    /// normals within normal_radius.
    int normal_half_window = 5;
    float normal_radius = 0.04f;  ///< [m]
    /// Organized scans' normals from their pixel windows; off: from the k-d tree within
    /// normal_radius, as for unorganized ones. Off for the tilting laser: near the beams that
    /// point along its tilt axis (at the sensor's height, on the walls to either side) its scan
    /// lines converge, a window of rows spans little more than the range noise across them, and
    /// the window's normal comes out nearly across the surface.
    bool organized_normals = true;
    RoomAxesParams axes;
    RoomStructureParams structure;
    FixtureParams fixtures;
    FrontSegmentation front_segmentation = FrontSegmentation::kRegionGrowing;
    ImageEdgeParams image_edges;  ///< outline evidence of organized scans
    FrontEdgeParams outline;      ///< kOutline
    FrontParams fronts;           ///< kRegionGrowing
    /// kRegionGrowing: grown fronts are then extended to their outlines (ExtendFrontsToOutlines
    /// with `outline`)
    bool extend_fronts = true;
    /// Parts of the faces that their outlines bound as fronts, outside every front of a fixture,
    /// become fronts without fixtures (AddFrontsFromGaps on the grid of `outline`)
    GapFrontParams gap_fronts;
    ArticulationParams articulation;
    ContainerParams containers;
    int num_threads = 0;  ///< 0 = all cores
    /// Throws InvalidArgument naming the first out-of-range field of any stage.
    void Validate() const;
};

/// The parameters tuned for a sensor (docs/kitchens.md lists them).
MapKitchenParams KitchenParamsFor(KitchenSensor sensor);

/// The parameters of articulation from an opened scan for a sensor: the laser's centimetre
/// range noise and sparser rows need looser distances, fewer points and larger coverage cells.
MotionParams MotionParamsFor(KitchenSensor sensor);

/// The sensor a set of scans looks like: a Kinect when a scan has colours; else a laser when a
/// scan has intensity or none is organized (an image); else (organized depth images without
/// colour) a Kinect.
KitchenSensor GuessKitchenSensor(const std::vector<PointCloud>& scans);

struct MapKitchenResult {
    KitchenMap map;
    /// The scans merged (in order, NaN points kept) with normals; map indices refer to it.
    PointCloud cloud;
    std::vector<std::size_t> scan_offsets;  ///< first point of each scan in `cloud`
    std::vector<float> ranges;  ///< per point of `cloud`: distance to its scan's sensor [m]
    std::vector<RejectedCluster> rejected_fixtures;    ///< clusters that became no fixture
    std::vector<FixtureCandidate> fixture_candidates;  ///< every measured fixture candidate
    double time_ms = 0.0;                              ///< whole pipeline [ms]
    /// Stage times in pipeline order: normals, axes, structure, fixtures, fronts, articulation,
    /// containers [ms]
    std::vector<std::pair<std::string, double>> timings;
};

/// Maps a kitchen from scans that share one frame (z up when they carry sensor positions, as
/// `multicue simulate kitchens` writes them). `classifier` types the furniture,
/// `fixture_classifier` decides which fixture candidates are handles and knobs, and
/// `joint_classifier` names the joints of fronts with a fixture (ClassifyJoints, after the
/// pieces are grouped; they are grouped again where a joint changed); nullptr: rules.
/// Throws InvalidArgument for bad parameters or a classifier of another kind or trained on other
/// features (before any work); DataError when there are no scans, no finite point, or no
/// vertical plane to look for furniture on.
MapKitchenResult MapKitchen(const std::vector<PointCloud>& scans, const MapKitchenParams& params,
                            const ml::Classifier* classifier = nullptr,
                            const ml::Classifier* fixture_classifier = nullptr,
                            const ml::Classifier* joint_classifier = nullptr);

/// Merges scans into one cloud with normals (image-space normals for organized scans when
/// `organized_normals`, else k-d tree normals): colours
/// of scans without colours get alpha 0, intensities of scans without intensity NaN. `offsets`
/// receives the first point of each scan, `ranges` each point's distance to its scan's sensor.
/// Throws DataError when there are no scans.
PointCloud MergeScansWithNormals(const std::vector<PointCloud>& scans,
                                 const MapKitchenParams& params, std::vector<std::size_t>& offsets,
                                 std::vector<float>& ranges);

/// Per-point classes and fronts of `map` (fills map.point_class and map.point_front).
void LabelMapPoints(KitchenMap& map, std::size_t num_points,
                    const std::vector<std::int32_t>& point_component);

}  // namespace multicue::mapping
