#include "multicue/mapping/kitchen_map.hpp"

#include <chrono>
#include <cmath>
#include <limits>

#include <fmt/format.h>

#include "multicue/core/exceptions.hpp"
#include "multicue/core/logging.hpp"
#include "multicue/search/kdtree.hpp"
#include "multicue/surface/normals.hpp"

namespace multicue::mapping {

const std::vector<std::string>& MapClassNames() {
    static const std::vector<std::string> names = {"none",  "wall", "floor", "ceiling", "worktop",
                                                   "table", "face", "front", "handle",  "knob"};
    return names;
}

const char* JointTypeName(JointType type) {
    switch (type) {
        case JointType::kRevolute:
            return "revolute";
        case JointType::kPrismatic:
            return "prismatic";
        case JointType::kUnknown:
            break;
    }
    return "unknown";
}

void MapKitchenParams::Validate() const {
    if (normal_half_window < 1 || normal_half_window > 100) {
        throw InvalidArgument(fmt::format(
            "map kitchen: normal_half_window must be in [1, 100], got {}", normal_half_window));
    }
    if (!(normal_radius > 0.0f) || !std::isfinite(normal_radius)) {
        throw InvalidArgument(
            fmt::format("map kitchen: normal_radius must be > 0, got {}", normal_radius));
    }
    if (num_threads < 0) {
        throw InvalidArgument(
            fmt::format("map kitchen: num_threads must be >= 0, got {}", num_threads));
    }
    axes.Validate();
    structure.Validate();
    fixtures.Validate();
    fronts.Validate();
    image_edges.Validate();
    outline.Validate();
    gap_fronts.Validate();
    articulation.Validate();
    containers.Validate();
}

MotionParams MotionParamsFor(KitchenSensor sensor) {
    MotionParams p;
    if (sensor == KitchenSensor::kLaser) {
        p.change_distance = 0.04f;
        p.plane_threshold = 0.03f;
        p.min_points = 10;
        p.coverage_cell = 0.05f;
    }
    return p;
}

MapKitchenParams KitchenParamsFor(KitchenSensor sensor) {
    MapKitchenParams p;
    if (sensor == KitchenSensor::kKinect) {
        // Disparity noise and its quantisation grow with the square of the range.
        p.normal_half_window = 7;
        p.structure.range_noise = 0.004f;
        p.fixtures.noise_floor = 0.002f;
        p.fixtures.range_noise = 0.0015f;
        // Colour: a thin handle barely out of the disparity noise still differs in grey level.
        p.fixtures.min_contrast = 40.0f;
        // A front grown over a gap into the next door, whose handle was missed, is cut at the
        // gap (the laser's coarser outlines cut through doors as often).
        p.gap_fronts.split_fixture_fronts = true;
        // A candidate the classifier doubts, with no fixture near it, is most often the handle
        // of a design it has not seen (chosen on the tune half; off for the laser, whose fronts
        // gained little there and whose hinges lost on held-out kitchens: docs/kitchens.md).
        p.fixtures.lone_min_confidence = 0.3f;
    }
    if (sensor == KitchenSensor::kLaser) {
        // Centimetre range noise and sparse rows: thicker planes, looser clusters; normals from
        // neighbourhoods in space, not from rows meeting at the tilt axis.
        p.organized_normals = false;
        p.normal_radius = 0.06f;
        p.structure.distance_threshold = 0.03f;
        p.structure.component_tolerance = 0.08f;
        p.structure.min_component_points = 20;
        p.structure.min_plane_points = 40;
        p.fixtures.min_height = 0.02f;
        p.fixtures.noise_floor = 0.01f;
        p.fixtures.residual_sigmas = 2.0f;
        p.fixtures.min_residual = 0.015f;
        p.fixtures.residual_cell = 0.025f;
        p.fixtures.background_cell = 0.05f;
        p.fixtures.background_tolerance = 0.02f;
        p.fixtures.surround_inner = 0.015f;
        p.fixtures.surround_outer = 0.08f;
        p.fixtures.cluster_tolerance = 0.03f;
        p.fixtures.min_points = 5;
        p.fixtures.min_contrast = 30.0f;  // remission (scaled to 0-255) of a handle's material
        p.fixtures.line_threshold = 0.015f;
        p.fixtures.circle_threshold = 0.01f;
        // The laser's classifier finds fewer handles than the Kinect's; a lower cut finds more,
        // and their fronts with them (chosen on the tune half, docs/kitchens.md).
        p.fixtures.min_confidence = 0.35f;
        p.outline.cell = 0.025f;
        p.outline.recess = 0.015f;
        p.outline.step = 0.03f;
        p.outline.hole_reach = 2;
        p.outline.margin = 0.03f;
        p.fronts.cue = AppearanceCue::kAuto;  // intensity (the laser has no colour), else none
        p.fronts.cell_size = 0.04f;
        p.fronts.seed_max = 0.08f;
        p.fronts.min_points = 8;
        p.gap_fronts.min_points = 15;
    }
    return p;
}

KitchenSensor GuessKitchenSensor(const std::vector<PointCloud>& scans) {
    bool intensity = false, organized = false;
    for (const auto& s : scans) {
        if (s.HasColors()) return KitchenSensor::kKinect;
        intensity = intensity || s.HasIntensity();
        organized = organized || s.IsOrganized();
    }
    return intensity || !organized ? KitchenSensor::kLaser : KitchenSensor::kKinect;
}

PointCloud MergeScansWithNormals(const std::vector<PointCloud>& scans, const MapKitchenParams& p,
                                 std::vector<std::size_t>& offsets, std::vector<float>& ranges) {
    if (scans.empty()) throw DataError("map kitchen: no scans");
    bool any_color = false, any_intensity = false;
    std::size_t total = 0;
    for (const auto& s : scans) {
        s.Validate();
        any_color = any_color || s.HasColors();
        any_intensity = any_intensity || s.HasIntensity();
        total += s.size();
    }
    PointCloud out;
    out.points.reserve(total);
    out.normals.reserve(total);
    if (any_color) out.colors.reserve(total);
    if (any_intensity) out.intensity.reserve(total);
    offsets.clear();
    ranges.clear();
    ranges.reserve(total);
    for (const auto& s : scans) {
        for (const auto& x : s.points) ranges.push_back((x - s.sensor_origin).norm());
        offsets.push_back(out.points.size());
        NormalsResult nr;
        if (s.IsOrganized() && p.organized_normals) {
            OrganizedNormalParams np;
            np.half_window = p.normal_half_window;
            np.depth_dependent_window = true;
            np.num_threads = p.num_threads;
            nr = EstimateNormalsOrganized(s, np);
        } else {
            const KdTree tree(s);
            NormalParams np;
            np.radius = p.normal_radius;
            np.num_threads = p.num_threads;
            nr = EstimateNormals(s, tree, np);
        }
        out.points.insert(out.points.end(), s.points.begin(), s.points.end());
        out.normals.insert(out.normals.end(), nr.normals.begin(), nr.normals.end());
        if (any_color) {
            if (s.HasColors()) {
                out.colors.insert(out.colors.end(), s.colors.begin(), s.colors.end());
            } else {
                out.colors.insert(out.colors.end(), s.size(), Color{0, 0, 0, 0});
            }
        }
        if (any_intensity) {
            if (s.HasIntensity()) {
                out.intensity.insert(out.intensity.end(), s.intensity.begin(), s.intensity.end());
            } else {
                out.intensity.insert(out.intensity.end(), s.size(),
                                     std::numeric_limits<float>::quiet_NaN());
            }
        }
    }
    if (scans.size() == 1) {
        out.width = scans[0].width;
        out.height = scans[0].height;
    } else {
        out.SetUnorganized();
    }
    out.sensor_origin = scans[0].sensor_origin;
    out.sensor_orientation = scans[0].sensor_orientation;
    return out;
}

void LabelMapPoints(KitchenMap& map, std::size_t n, const std::vector<std::int32_t>& component) {
    map.point_class.assign(n, MapClass::kNone);
    map.point_front.assign(n, 0);
    for (std::size_t i = 0; i < n && i < component.size(); ++i) {
        if (component[i] >= 0) {
            map.point_class[i] = map.components[static_cast<std::size_t>(component[i])].label;
        }
    }
    for (std::size_t f = 0; f < map.fronts.size(); ++f) {
        for (const Index i : map.fronts[f].indices) {
            map.point_class[i] = MapClass::kFront;
            map.point_front[i] = static_cast<std::uint32_t>(f + 1);
        }
    }
    for (const Fixture& fx : map.fixtures) {
        const MapClass c = fx.type == FixtureType::kHandle ? MapClass::kHandle : MapClass::kKnob;
        for (const Index i : fx.indices) map.point_class[i] = c;
    }
}

MapKitchenResult MapKitchen(const std::vector<PointCloud>& scans, const MapKitchenParams& p,
                            const ml::Classifier* classifier,
                            const ml::Classifier* fixture_classifier,
                            const ml::Classifier* joint_classifier) {
    p.Validate();
    if (classifier != nullptr) CheckContainerClassifier(*classifier);
    if (fixture_classifier != nullptr) CheckFixtureClassifier(*fixture_classifier);
    if (joint_classifier != nullptr) CheckJointClassifier(*joint_classifier);
    using Clock = std::chrono::steady_clock;
    const auto t0 = Clock::now();
    auto last = t0;
    MapKitchenResult r;
    auto stage = [&](const char* name) {
        const auto now = Clock::now();
        r.timings.emplace_back(name, std::chrono::duration<double, std::milli>(now - last).count());
        last = now;
    };
    // Normals per scan, scans merged.
    r.cloud = MergeScansWithNormals(scans, p, r.scan_offsets, r.ranges);
    if (!r.cloud.HasFinite()) throw DataError("map kitchen: the scans hold no finite point");
    stage("normals");
    KitchenMap& map = r.map;
    // The room's main axes (RANSAC on the normal sphere).
    const RoomAxesResult axes = EstimateRoomAxes(r.cloud, p.axes);
    if (!axes.found) throw DataError("map kitchen: no dominant surface directions (room axes)");
    map.frame = axes.frame;
    stage("axes");
    // Floor, ceiling, walls, worktops and tables, furniture faces.
    RoomStructureParams structure_params = p.structure;
    structure_params.num_threads = p.num_threads;
    RoomStructure structure = SegmentRoomStructure(r.cloud, map.frame, structure_params, r.ranges);
    map.floor_height = structure.floor_height;
    map.ceiling_height = structure.ceiling_height;
    bool vertical = false;
    for (const auto& c : structure.components) vertical = vertical || c.axis != 2;
    if (!vertical) throw DataError("map kitchen: no vertical planes (walls or furniture faces)");
    stage("structure");
    // Handles and knobs in front of the faces.
    FixtureParams fixture_params = p.fixtures;
    fixture_params.num_threads = p.num_threads;
    FixtureResult fixtures =
        DetectFixtures(r.cloud, map.frame, structure, fixture_params, r.ranges, fixture_classifier);
    map.fixtures = std::move(fixtures.fixtures);
    r.rejected_fixtures = std::move(fixtures.rejected);
    r.fixture_candidates = std::move(fixtures.candidates);
    stage("fixtures");
    // Door and drawer fronts: regions grown from the fixtures and then out to their outlines,
    // or rectangles between the outlines around the fixtures.
    const bool outline = p.front_segmentation == FrontSegmentation::kOutline;
    FrontEvidence evidence;
    if (outline || p.extend_fronts || p.gap_fronts.enabled) {
        evidence.point_face = std::move(fixtures.point_face);
        evidence.point_residual = std::move(fixtures.point_residual);
        evidence.image_edge.assign(r.cloud.size(), 0);
        // Scans without an image (unorganized) show the outlines by their appearance instead.
        std::vector<float> look;
        bool any_unorganized = false;
        for (const auto& scan : scans) any_unorganized = any_unorganized || !scan.IsOrganized();
        if (any_unorganized) {
            try {
                look = AppearanceValues(r.cloud, p.fronts.cue, p.fronts.intensity_scale);
                evidence.appearance.assign(r.cloud.size(), std::numeric_limits<float>::quiet_NaN());
            } catch (const DataError&) {
                look.clear();  // no colours or intensity of the cue's kind: heights only
            }
        }
        for (std::size_t k = 0; k < scans.size(); ++k) {
            const std::vector<std::uint8_t> e = ImageEdges(scans[k], p.image_edges);
            const auto at = static_cast<long>(r.scan_offsets[k]);
            std::copy(e.begin(), e.end(), evidence.image_edge.begin() + at);
            if (!look.empty() && !scans[k].IsOrganized()) {
                std::copy(look.begin() + at, look.begin() + at + static_cast<long>(scans[k].size()),
                          evidence.appearance.begin() + at);
            }
        }
    }
    if (outline) {
        map.fronts =
            FrontsFromEdges(r.cloud, map.frame, structure, map.fixtures, evidence, p.outline);
    } else {
        map.fronts = SegmentFronts(r.cloud, map.frame, structure, map.fixtures, p.fronts, &evidence,
                                   p.outline);
        if (p.extend_fronts) {
            ExtendFrontsToOutlines(r.cloud, map.frame, structure, map.fixtures, evidence,
                                   map.fronts, p.outline);
        }
    }
    // Fronts whose fixture was missed: the rest of each face cut along its outlines.
    if (p.gap_fronts.enabled) {
        AddFrontsFromGaps(r.cloud, map.frame, structure, map.fixtures, evidence, map.fronts,
                          p.outline, p.gap_fronts);
    }
    MergeNestedFronts(structure, map.fronts, p.fronts);
    ClaimUnexplainedPoints(r.cloud, map.frame, structure, map.fixtures, map.fronts, p.fronts);
    stage("fronts");
    // How each front opens, from its fixture and the fronts around it (which are read for their
    // rectangles and fixtures only, so the order does not matter).
    for (std::size_t i = 0; i < map.fronts.size(); ++i) {
        map.fronts[i].articulation = ArticulationFromFixtures(
            map.fronts, i, map.fixtures, map.frame, map.floor_height, p.articulation);
        map.fronts[i].articulation.hinge_seen =
            HingeEdgeSeen(map.fronts[i], scans, r.scan_offsets, p.articulation);
    }
    stage("articulation");
    // Furniture pieces, kitchenettes and container types.
    map.components = std::move(structure.components);
    GroupFurniture(map, p.containers);
    if (joint_classifier != nullptr) {
        // The learned joints read the pieces; a changed joint can change how fronts group.
        const std::vector<std::size_t> changed =
            ClassifyJoints(map, *joint_classifier, p.articulation);
        for (const std::size_t i : changed) {
            map.fronts[i].articulation.hinge_seen =
                HingeEdgeSeen(map.fronts[i], scans, r.scan_offsets, p.articulation);
        }
        if (!changed.empty()) GroupFurniture(map, p.containers);
    }
    TypeContainers(map, classifier, p.containers);
    LabelMapPoints(map, r.cloud.size(), structure.point_component);
    stage("containers");
    r.time_ms = std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
    LogInfo("map kitchen: {} components, {} fixtures, {} fronts, {} pieces in {:.0f} ms",
            map.components.size(), map.fixtures.size(), map.fronts.size(), map.furniture.size(),
            r.time_ms);
    return r;
}

}  // namespace multicue::mapping
