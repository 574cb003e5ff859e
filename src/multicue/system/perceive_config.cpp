// The configuration of the table-top pipeline: one table per parameter struct, each row the key
// (the field's own name), the field and its meaning. The same rows read a file, print the
// defaults (`multicue config --dump`) and write the parameter reference (`--markdown`).

#include <string>
#include <vector>

#include "multicue/system/perceive.hpp"

namespace multicue {
namespace {

using io::ConfigSection;

// Every table, declared first: tables nest.
void Read(ConfigSection& s, OrganizedNormalParams& p);
void Read(ConfigSection& s, NormalParams& p);
void Read(ConfigSection& s, FrameNormalParams& p);
void Read(ConfigSection& s, SupportPlaneParams& p);
void Read(ConfigSection& s, PrismParams& p);
void Read(ConfigSection& s, ObjectClusteringParams& p);
void Read(ConfigSection& s, RegionGrowingParams& p);
void Read(ConfigSection& s, ConvexitySplitParams& p);
void Read(ConfigSection& s, PartSegmentationParams& p);
void Read(ConfigSection& s, OcclusionMergeParams& p);
void Read(ConfigSection& s, CategoryParams& p);
void Read(ConfigSection& s, PartGraphRecognitionParams& p);
void Read(ConfigSection& s, CategorizationParams& p);
void Read(ConfigSection& s, BoxFitParams& p);
void Read(ConfigSection& s, SacParams& p);
void Read(ConfigSection& s, CylinderModelParams& p);
void Read(ConfigSection& s, GreedyTriangulationParams& p);
void Read(ConfigSection& s, RsdParams& p);
void Read(ConfigSection& s, RotationalFitParams& p);
void Read(ConfigSection& s, VerificationParams& p);
void Read(ConfigSection& s, ConcentricMergeParams& p);
void Read(ConfigSection& s, ContainedMergeParams& p);
void Read(ConfigSection& s, StackedSplitParams& p);
void Read(ConfigSection& s, TouchingSplitParams& p);
void Read(ConfigSection& s, PartCountParams& p);
void Read(ConfigSection& s, ModelParams& p);

// A row: key = the field's name.
#define MC_FIELD(name, help) s.Get(#name, p.name, help)
// A nested struct: its own table in the section of the field's name.
#define MC_NODE(name) Node(s, #name, p.name)
// An optional step: its "enabled" switch, then its own table.
#define MC_SWITCH(name, help) Node(s, #name, p.name, help)

template <typename P>
void Node(ConfigSection& s, const char* key, P& p) {
    auto sub = s.Section(key);
    Read(sub, p);
}

template <typename P>
void Node(ConfigSection& s, const char* key, Switchable<P>& p, const char* help) {
    auto sub = s.Section(key);
    sub.Get("enabled", p.enabled, help);
    Read(sub, static_cast<P&>(p));
}

void Read(ConfigSection& s, OrganizedNormalParams& p) {
    MC_FIELD(half_window, "half-size of the pixel window [px]");
    MC_FIELD(stride, "step between the pixels read, 0 = automatic [px]");
    MC_FIELD(depth_dependent_window, "scale the window with depth");
    MC_FIELD(max_depth_change, "neighbours within this depth difference at 1 m [m]");
}

void Read(ConfigSection& s, NormalParams& p) {
    MC_FIELD(k, "neighbours of the PCA [points]");
    MC_FIELD(radius, "neighbourhood radius [m], 0 = use k only");
}

void Read(ConfigSection& s, FrameNormalParams& p) {
    MC_NODE(organized);
    MC_NODE(unorganized);
}

void Read(ConfigSection& s, SupportPlaneParams& p) {
    MC_FIELD(up,
             "up in the cloud's frame, null = from VIEWPOINT, the camera convention or the "
             "dominant plane");
    MC_FIELD(max_tilt_deg, "table normal within this angle of a given or world up [deg]");
    MC_FIELD(camera_tilt_deg, "in the sensor frame: table normal within this angle of -y [deg]");
    MC_FIELD(distance_threshold, "plane inlier distance [m]");
    MC_FIELD(max_candidates, "planes extracted before choosing");
    MC_FIELD(min_inlier_fraction, "a candidate plane holds at least this share of the points");
    MC_FIELD(size_ratio_to_compete,
             "planes this large relative to the largest compete on nearness to the viewpoint");
    MC_FIELD(raised_gap,
             "a smaller plane this much nearer to the viewpoint than the largest is a table on "
             "the floor and wins (0 = off) [m]");
    MC_FIELD(raised_ratio, "... if it holds this share of the largest plane's inliers [-]");
    MC_FIELD(max_samples, "points used by the robust fit");
    MC_FIELD(cluster_tolerance, "the table is the largest connected patch of plane inliers [m]");
    MC_FIELD(seed, "sample consensus seed");
}

void Read(ConfigSection& s, PrismParams& p) {
    MC_FIELD(min_height, "lowest object point above the table [m]");
    MC_FIELD(max_height, "highest object point above the table [m]");
}

void Read(ConfigSection& s, ObjectClusteringParams& p) {
    MC_FIELD(tolerance, "points closer than this are one object [m]");
    MC_FIELD(min_points, "smaller clusters (and pieces of splits) are not objects");
    MC_FIELD(max_points, "larger clusters are not objects");
    MC_FIELD(organized_half_window,
             "organized clustering reach in pixels; 2 bridges one-pixel gaps");
}

void Read(ConfigSection& s, RegionGrowingParams& p) {
    MC_FIELD(radius, "neighbourhood radius, delta of section 4.2.1 [m]");
    MC_FIELD(k, "if > 0, at most k neighbours within the radius");
    MC_FIELD(max_angle_deg, "angle to the part's seed normal, alpha [deg]");
    MC_FIELD(min_part_size, "smaller parts are merged into a neighbour [points]");
    MC_FIELD(discard_small_parts, "drop parts still too small after merging");
}

void Read(ConfigSection& s, ConvexitySplitParams& p) {
    MC_FIELD(patch_size, "voxel patch edge [m]");
    MC_FIELD(smooth_angle_deg, "patches with normals closer than this always join [deg]");
    MC_FIELD(min_convex_share, "parts join when this share of their border is convex");
    MC_FIELD(min_border, "patch pairs needed to judge a border");
    MC_FIELD(bend_angle_deg,
             "concave borders with a median patch angle below this are bends [deg]; 0 = off");
    MC_FIELD(max_top_difference,
             "groups across a bend join when their tops differ less than this [m]");
}

void Read(ConfigSection& s, PartSegmentationParams& p) {
    MC_NODE(region_growing);
    MC_SWITCH(convexity, "split hypotheses where their parts meet in concave creases");
}

void Read(ConfigSection& s, OcclusionMergeParams& p) {
    MC_FIELD(depth_margin, "gap pixels this much nearer than both [m]");
    MC_FIELD(min_near_share, "share of nearer pixels in an occluded row");
    MC_FIELD(min_occluded_share, "share of the shared rows that must be occluded");
    MC_FIELD(min_rows, "fewest occluded rows for a merge");
    MC_FIELD(max_gap, "largest median 3D distance across the gap [m]");
    MC_FIELD(min_height_overlap, "overlap of the height ranges over the smaller one");
    MC_FIELD(surface_distance, "surface continuation distance [m]");
    MC_FIELD(surface_angle_deg, "surface continuation angle [deg]");
    MC_FIELD(min_explained_share, "share of a fragment the other's surface must explain");
    MC_FIELD(min_cylinder_radius, "smallest cylinder radius [m]");
    MC_FIELD(max_cylinder_radius, "largest cylinder radius [m]");
    MC_FIELD(cylinder_iterations, "cylinder RANSAC sample cap");
}

void Read(ConfigSection& s, CategoryParams& p) {
    MC_FIELD(min_points, "fewer usable points give category none");
    MC_FIELD(max_points, "evidence uses at most this many points");
    MC_FIELD(axis_angle_deg, "normal this close to a box axis is box-like [deg]");
    MC_FIELD(planar_part_angle_deg, "planar part tolerance [deg]");
    MC_FIELD(fit_threshold, "cylinder and sphere inlier distance [m]");
    MC_FIELD(normal_weight, "normal distance weight of those fits");
    MC_FIELD(min_radius, "smallest cylinder or sphere radius [m]");
    MC_FIELD(max_radius, "largest cylinder or sphere radius [m]");
    MC_FIELD(upright_angle_deg, "upright cylinder axis tolerance [deg]");
    MC_FIELD(lying_angle_deg, "lying cylinder axis tolerance [deg]");
    MC_FIELD(max_iterations, "RANSAC sample cap");
    MC_FIELD(min_side_ratio, "cylinder side share scoring 0");
    MC_FIELD(full_side_ratio, "cylinder side share scoring fully");
    MC_FIELD(size_tolerance, "diameter vs extent tolerance factor");
    MC_FIELD(flat_ratio, "flat if e2/e3 >= this");
    MC_FIELD(box_ratio, "box if e2/e3 < this");
    MC_FIELD(flat_long_ratio, "in between: flat if e1/e3 > this");
    MC_FIELD(boundary_softness, "slope of the soft box/flat split");
    MC_FIELD(plate_thin_ratio, "thickness/diameter fully thin");
    MC_FIELD(plate_thick_ratio, "thickness/diameter not thin");
    MC_FIELD(plate_low_height, "objects up to this high may be plates [m]");
    MC_FIELD(plate_high_height, "objects from this high are no plates [m]");
    MC_FIELD(sphere_box_axis_area, "sphere score fades from this axis_area");
    MC_FIELD(sphere_box_axis_area_max, "... to 0 at this axis_area");
    MC_FIELD(round_fill, "footprint fill up to this is round");
    MC_FIELD(square_fill, "footprint fill from this is square");
    MC_FIELD(min_evidence, "other wins below this score");
    MC_FIELD(sharpness, "exponent on scores before normalising");
    MC_FIELD(seed, "RANSAC seed");
}

void Read(ConfigSection& s, PartGraphRecognitionParams& p) {
    MC_FIELD(max_parts, "largest group of parts classified in a scene");
    MC_FIELD(k, "neighbours voting per group");
    MC_FIELD(balanced, "divide votes by the category's share of the model's rows");
    MC_FIELD(within_groups, "only groups of parts inside one perceived object vote");
    MC_FIELD(group_weight, "weight of each whole object's own vote (0: none)");
    auto priors = s.Section("category_priors");
    for (std::size_t c = 1; c < kNumCategories; ++c) {
        priors.Get(std::string(kCategoryNames[c]), p.category_priors[c],
                   "prior weight of this category's part-graph votes (>= 0)");
    }
}

void Read(ConfigSection& s, CategorizationParams& p) {
    std::vector<std::string_view> names;
    for (Categoriser c :
         {Categoriser::kRules, Categoriser::kPartGraph, Categoriser::kPartGraphRules,
          Categoriser::kThreeExperts, Categoriser::kStacked}) {
        names.push_back(CategoriserName(c));
    }
    std::string categoriser(CategoriserName(p.categoriser));
    s.GetChoice("categoriser", categoriser, names, "who decides the categories");
    p.categoriser = ParseCategoriser(categoriser);
    MC_FIELD(part_graph_model,
             "part-graph model file (empty: the default model, trained once and cached)");
    MC_NODE(rules);
    MC_NODE(part_graph);
    MC_FIELD(part_graph_weight,
             "weight of the part-graph votes against the rules in part-graph+rules, [0, 1]");
    MC_FIELD(expert_weights,
             "weights of the rules, part-graph and cluster experts in part-graph+rules+cluster");
    MC_FIELD(cluster_k,
             "neighbours of the whole-object expert (part-graph+rules+cluster, stacked)");
}

void Read(ConfigSection& s, BoxFitParams& p) {
    MC_FIELD(inlier_threshold, "box surface inlier distance [m]");
    MC_FIELD(use_normals, "orient boxes by their side faces' normals");
    MC_FIELD(face_angle_deg, "face point normal tolerance [deg]");
    MC_FIELD(min_face_points, "points needed to place a face");
}

void Read(ConfigSection& s, SacParams& p) {
    MC_FIELD(distance_threshold, "RANSAC inlier distance [m]");
    MC_FIELD(max_iterations, "RANSAC sample cap");
    MC_FIELD(normal_distance_weight, "normal term weight");
    MC_FIELD(seed, "RANSAC seed");
}

void Read(ConfigSection& s, CylinderModelParams& p) {
    MC_NODE(sac);
    MC_FIELD(min_radius, "smallest radius [m]");
    MC_FIELD(max_radius, "largest radius [m]");
    MC_FIELD(upright_angle_deg, "upright prior tolerance [deg]");
    MC_FIELD(allow_free_axis, "also try a free axis");
    MC_FIELD(free_axis_gain, "free axis must explain this factor more");
    MC_FIELD(extend_to_support, "upright cylinders reach the table");
    MC_FIELD(cap_angle_deg, "cap point normal tolerance [deg]");
    MC_FIELD(min_cap_points, "points needed to place a cap");
    MC_FIELD(inlier_threshold, "surface distance for inlier_ratio [m]");
}

void Read(ConfigSection& s, GreedyTriangulationParams& p) {
    MC_FIELD(search_radius, "longest edge and neighbourhood [m]");
    MC_FIELD(mu, "neighbourhood / nearest distance");
    MC_FIELD(max_surface_angle_deg, "largest angle between connected normals [deg]");
}

void Read(ConfigSection& s, RsdParams& p) { MC_FIELD(radius, "RSD neighbourhood radius [m]"); }

void Read(ConfigSection& s, RotationalFitParams& p) {
    MC_FIELD(max_tilt_deg, "axis within this angle of up [deg]");
    MC_FIELD(max_points, "points used by the axis search");
    MC_FIELD(grid_directions, "coarse axis directions (sphere)");
    MC_FIELD(line_threshold, "normal line to axis distance [m]");
    MC_FIELD(profile_step, "contour height bin [m]");
    MC_FIELD(inlier_threshold, "surface distance of an inlier [m]");
    MC_FIELD(profile_refinement, "refine the axis by the thinnest contour and the level rim");
}

void Read(ConfigSection& s, VerificationParams& p) {
    MC_FIELD(voxel_size, "occupancy cell [m]");
    MC_FIELD(margin, "grid margin around the model [m]");
    MC_FIELD(sample_spacing, "surface sample spacing [m]");
    MC_FIELD(tolerance_voxels, "occupied cells this close verify a sample [cells]");
    MC_FIELD(max_invalid_ratio, "models with a larger share of surface in free space are rejected");
}

void Read(ConfigSection& s, ConcentricMergeParams& p) {
    MC_FIELD(enabled,
             "merge objects whose cylinders share their axis (inside and outside of a pot)");
    MC_FIELD(angle_deg, "axes parallel within [deg]");
    MC_FIELD(distance, "axis to axis at most [m]");
    MC_FIELD(radius_ratio, "radii differ by at most this share of the larger one");
}

void Read(ConfigSection& s, ContainedMergeParams& p) {
    MC_FIELD(enabled, "join objects lying inside a container's cylinder or surface of revolution");
    MC_FIELD(margin, "the container's solid enlarged by this [m]");
    MC_FIELD(min_share, "share of the object's points inside");
}

void Read(ConfigSection& s, StackedSplitParams& p) {
    MC_FIELD(enabled,
             "split box objects with two horizontal faces at different heights into two boxes");
    MC_FIELD(min_face_points, "points of each horizontal face");
    MC_FIELD(min_step, "height between the faces at least [m]");
    MC_FIELD(min_gain, "two boxes must explain this much larger a share of the points than one");
}

void Read(ConfigSection& s, TouchingSplitParams& p) {
    MC_FIELD(enabled, "split box objects that one box explains poorly into two touching boxes");
    MC_FIELD(min_part_points, "parts taking part in the splits");
    MC_FIELD(max_parts, "largest parts tried (2 to 12)");
    MC_FIELD(max_overlap, "the two solid boxes overlap by at most this share");
    MC_FIELD(min_gain, "two models must explain this much larger a share of the points than one");
    MC_FIELD(max_points, "points used per evaluation");
    MC_FIELD(round_enabled,
             "split round objects that one cylinder explains poorly into two cylinders");
}

void Read(ConfigSection& s, PartCountParams& p) {
    MC_FIELD(flat_mean, "Poisson mean of parts of flat objects");
    MC_FIELD(round_mean, "Poisson mean of parts of round objects");
    MC_FIELD(other_mean, "Poisson mean of parts of other objects");
}

void Read(ConfigSection& s, ModelParams& p) {
    MC_FIELD(min_inlier_ratio,
             "primitives explaining a smaller share of their points are replaced");
    MC_FIELD(mesh_fallback,
             "replace rejected primitives by a triangulated mesh of the object's points");
    MC_NODE(mesh);
    MC_FIELD(mesh_max_points, "triangulate at most this many points (even stride)");
    MC_FIELD(min_attached_points,
             "outliers of a kept primitive (a handle) are meshed and attached from this many, 0 = "
             "never");
    MC_FIELD(guided_fits,
             "box/cylinder fits sample by RSD and weight by part-graph part probabilities");
    MC_NODE(guided_rsd);
    MC_NODE(box);
    MC_NODE(cylinder);
    MC_SWITCH(
        rotational,
        "surfaces of revolution for cylinder/sphere/other objects whose primitive fits poorly");
    MC_SWITCH(verification, "verify models against the frame's free space");
    MC_NODE(concentric);
    MC_NODE(contained);
    MC_NODE(stacked);
    MC_NODE(touching);
    MC_FIELD(several_min_ratio,
             "splits are tried when the part count is this much likelier for two objects");
    MC_NODE(part_counts);
}

#undef MC_FIELD
#undef MC_NODE
#undef MC_SWITCH

}  // namespace

std::vector<std::pair<std::string, std::string>> PerceiveRenamedKeys() {
    std::vector<std::pair<std::string, std::string>> renamed = {
        {"normals.k", "normals.unorganized.k"},
        {"normals.radius", "normals.unorganized.radius"},
        {"objects.cluster_tolerance", "clustering.tolerance"},
        {"objects", "clustering"},
        {"convexity", "parts.convexity"},
        {"category.part_graph_max_parts", "category.part_graph.max_parts"},
        {"category.part_graph_k", "category.part_graph.k"},
        {"category.part_graph_balanced", "category.part_graph.balanced"},
        {"category.part_graph_within_objects", "category.part_graph.within_groups"},
        {"category.part_graph_object_weight", "category.part_graph.group_weight"},
        {"category.part_graph_priors", "category.part_graph.category_priors"},
        {"box", "models.box"},
        {"cylinder.distance_threshold", "models.cylinder.sac.distance_threshold"},
        {"cylinder.max_iterations", "models.cylinder.sac.max_iterations"},
        {"cylinder.normal_distance_weight", "models.cylinder.sac.normal_distance_weight"},
        {"cylinder.seed", "models.cylinder.sac.seed"},
        {"cylinder", "models.cylinder"},
        {"models.mesh_search_radius", "models.mesh.search_radius"},
        {"models.mesh_mu", "models.mesh.mu"},
        {"models.mesh_max_surface_angle_deg", "models.mesh.max_surface_angle_deg"},
        {"models.guided_rsd_radius", "models.guided_rsd.radius"},
    };
    for (const char* key :
         {"radius", "k", "max_angle_deg", "min_part_size", "discard_small_parts"}) {
        renamed.emplace_back(std::string("parts.") + key,
                             std::string("parts.region_growing.") + key);
    }
    // The rules' keys, read off their own table.
    ConfigSection rules = ConfigSection::Dump();
    CategoryParams defaults;
    Read(rules, defaults);
    for (const auto& key : rules.RecordedKeys()) {
        renamed.emplace_back("category." + key, "category.rules." + key);
    }
    return renamed;
}

void ReadPerceiveParams(ConfigSection& config, PerceiveParams& p) {
    for (const auto& [from, to] : PerceiveRenamedKeys()) config.Rename(from, to);
    ConfigSection& s = config;
    s.Get("threads", p.num_threads, "worker threads, 0 = all cores");
    Node(s, "normals", p.normals);
    Node(s, "support", p.support);
    Node(s, "prism", p.prism);
    Node(s, "clustering", p.clustering);
    Node(s, "parts", p.parts);
    Node(s, "occlusion", p.occlusion,
         "join fragments of an object that a nearer object cuts in two");
    Node(s, "category", p.category);
    Node(s, "models", p.models);
}

}  // namespace multicue
