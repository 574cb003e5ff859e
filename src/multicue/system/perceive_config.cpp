// Parameter file of the table-top pipeline: one section per stage, keys named as the fields.

#include "multicue/system/perceive.hpp"

namespace multicue {

void ReadPerceiveParams(io::ConfigSection& config, PerceiveParams& p) {
    config.Get("threads", p.num_threads, "worker threads, 0 = all cores");

    auto normals = config.Section("normals");
    normals.Get("k", p.normals.k, "unorganized clouds: neighbours of the PCA [points]");
    normals.Get("radius", p.normals.radius,
                "unorganized clouds: neighbourhood radius [m], 0 = use k only");
    auto organized = normals.Section("organized");
    organized.Get("half_window", p.organized_normals.half_window,
                  "organized frames: half-size of the pixel window [px]");
    organized.Get("stride", p.organized_normals.stride,
                  "organized frames: step between the pixels read, 0 = automatic [px]");
    organized.Get("depth_dependent_window", p.organized_normals.depth_dependent_window,
                  "organized frames: scale the window with depth");
    organized.Get("max_depth_change", p.organized_normals.max_depth_change,
                  "organized frames: neighbours within this depth difference at 1 m [m]");

    auto support = config.Section("support");
    support.Get("up", p.support.up,
                "up in the cloud's frame, null = from VIEWPOINT, the camera convention or the "
                "dominant plane");
    support.Get("max_tilt_deg", p.support.max_tilt_deg,
                "table normal within this angle of a given or world up [deg]");
    support.Get("camera_tilt_deg", p.support.camera_tilt_deg,
                "in the sensor frame: table normal within this angle of -y [deg]");
    support.Get("distance_threshold", p.support.distance_threshold, "plane inlier distance [m]");
    support.Get("max_candidates", p.support.max_candidates, "planes extracted before choosing");
    support.Get("min_inlier_fraction", p.support.min_inlier_fraction,
                "a candidate plane holds at least this share of the points");
    support.Get("size_ratio_to_compete", p.support.size_ratio_to_compete,
                "planes this large relative to the largest compete on nearness to the viewpoint");
    support.Get("raised_gap", p.support.raised_gap,
                "a smaller plane this much nearer to the viewpoint than the largest is a table on "
                "the floor and wins (0 = off) [m]");
    support.Get("raised_ratio", p.support.raised_ratio,
                "... if it holds this share of the largest plane's inliers [-]");
    support.Get("max_samples", p.support.max_samples, "points used by the robust fit");
    support.Get("cluster_tolerance", p.support.cluster_tolerance,
                "the table is the largest connected patch of plane inliers [m]");
    support.Get("seed", p.support.seed, "sample consensus seed");

    auto prism = config.Section("prism");
    prism.Get("min_height", p.prism.min_height, "lowest object point above the table [m]");
    prism.Get("max_height", p.prism.max_height, "highest object point above the table [m]");

    auto objects = config.Section("objects");
    objects.Get("cluster_tolerance", p.cluster_tolerance, "Euclidean clustering tolerance [m]");
    objects.Get("min_points", p.min_object_points, "smaller clusters are not objects");
    objects.Get("max_points", p.max_object_points, "larger clusters are not objects");
    objects.Get("organized_half_window", p.organized_half_window,
                "organized clustering reach in pixels; 2 bridges one-pixel gaps");

    auto parts = config.Section("parts");
    parts.Get("radius", p.parts.radius, "region growing distance delta [m] (section 4.2.1)");
    parts.Get("k", p.parts.k, "if > 0, at most k neighbours within the radius");
    parts.Get("max_angle_deg", p.parts.max_angle_deg, "angle to the seed normal, alpha [deg]");
    parts.Get("min_part_size", p.parts.min_part_size, "smaller parts are merged [points]");
    parts.Get("discard_small_parts", p.parts.discard_small_parts,
              "drop parts still too small after merging");

    auto convexity = config.Section("convexity");
    convexity.Get("enabled", p.split_concave,
                  "split hypotheses where their parts meet in concave creases");
    convexity.Get("patch_size", p.convexity.patch_size, "voxel patch edge [m]");
    convexity.Get("smooth_angle_deg", p.convexity.smooth_angle_deg,
                  "patches with normals closer than this always join [deg]");
    convexity.Get("min_convex_share", p.convexity.min_convex_share,
                  "parts join when this share of their border is convex");
    convexity.Get("min_border", p.convexity.min_border, "patch pairs needed to judge a border");
    convexity.Get("bend_angle_deg", p.convexity.bend_angle_deg,
                  "concave borders with a median patch angle below this are bends [deg]; 0 = off");
    convexity.Get("max_top_difference", p.convexity.max_top_difference,
                  "groups across a bend join when their tops differ less than this [m]");

    auto occlusion = config.Section("occlusion");
    auto& o = p.occlusion;
    occlusion.Get("enabled", p.merge_occluded,
                  "join fragments of an object that a nearer object cuts in two");
    occlusion.Get("depth_margin", o.depth_margin, "gap pixels this much nearer than both [m]");
    occlusion.Get("min_near_share", o.min_near_share, "share of nearer pixels in an occluded row");
    occlusion.Get("min_occluded_share", o.min_occluded_share,
                  "share of the shared rows that must be occluded");
    occlusion.Get("min_rows", o.min_rows, "fewest occluded rows for a merge");
    occlusion.Get("max_gap", o.max_gap, "largest median 3D distance across the gap [m]");
    occlusion.Get("min_height_overlap", o.min_height_overlap,
                  "overlap of the height ranges over the smaller one");
    occlusion.Get("surface_distance", o.surface_distance, "surface continuation distance [m]");
    occlusion.Get("surface_angle_deg", o.surface_angle_deg, "surface continuation angle [deg]");
    occlusion.Get("min_explained_share", o.min_explained_share,
                  "share of a fragment the other's surface must explain");
    occlusion.Get("min_cylinder_radius", o.min_cylinder_radius, "smallest cylinder radius [m]");
    occlusion.Get("max_cylinder_radius", o.max_cylinder_radius, "largest cylinder radius [m]");
    occlusion.Get("cylinder_iterations", o.cylinder_iterations, "cylinder RANSAC sample cap");

    auto cat = config.Section("category");
    cat.Get("categoriser", p.categoriser,
            "rules, part-graph, part-graph+rules, part-graph+rules+cluster or stacked "
            "(docs/part-graph.md)");
    cat.Get("part_graph_model", p.part_graph_model,
            "part-graph model file (empty: the default model, trained once and cached)");
    cat.Get("part_graph_max_parts", p.part_graph_recognition.max_parts,
            "largest group of parts classified in a scene");
    cat.Get("part_graph_k", p.part_graph_recognition.k, "neighbours voting per group");
    cat.Get("part_graph_balanced", p.part_graph_recognition.balanced,
            "divide votes by the category's share of the model's rows");
    cat.Get("part_graph_within_objects", p.part_graph_recognition.within_groups,
            "only groups of parts inside one perceived object vote");
    cat.Get("part_graph_object_weight", p.part_graph_recognition.group_weight,
            "weight of each whole object's own vote (0: none)");
    auto priors = cat.Section("part_graph_priors");
    for (std::size_t c = 1; c < kNumCategories; ++c) {
        priors.Get(std::string(kCategoryNames[c]), p.part_graph_recognition.category_priors[c],
                   "prior weight of this category's part-graph votes (>= 0)");
    }
    cat.Get("part_graph_weight", p.part_graph_weight,
            "weight of the part-graph votes against the rules in part-graph+rules, [0, 1]");
    cat.Get("expert_weights", p.expert_weights,
            "weights of the rules, part-graph and cluster experts in part-graph+rules+cluster");
    cat.Get("cluster_k", p.cluster_k,
            "neighbours of the whole-object expert (part-graph+rules+cluster, stacked)");
    auto& c = p.category;
    cat.Get("min_points", c.min_points, "fewer usable points give category none");
    cat.Get("max_points", c.max_points, "evidence uses at most this many points");
    cat.Get("axis_angle_deg", c.axis_angle_deg, "normal this close to a box axis is box-like");
    cat.Get("planar_part_angle_deg", c.planar_part_angle_deg, "planar part tolerance [deg]");
    cat.Get("fit_threshold", c.fit_threshold, "cylinder and sphere inlier distance [m]");
    cat.Get("normal_weight", c.normal_weight, "normal distance weight of those fits");
    cat.Get("min_radius", c.min_radius, "smallest cylinder or sphere radius [m]");
    cat.Get("max_radius", c.max_radius, "largest cylinder or sphere radius [m]");
    cat.Get("upright_angle_deg", c.upright_angle_deg, "upright cylinder axis tolerance [deg]");
    cat.Get("lying_angle_deg", c.lying_angle_deg, "lying cylinder axis tolerance [deg]");
    cat.Get("max_iterations", c.max_iterations, "RANSAC sample cap");
    cat.Get("min_side_ratio", c.min_side_ratio, "cylinder side share scoring 0");
    cat.Get("full_side_ratio", c.full_side_ratio, "cylinder side share scoring fully");
    cat.Get("size_tolerance", c.size_tolerance, "diameter vs extent tolerance factor");
    cat.Get("flat_ratio", c.flat_ratio, "flat if e2/e3 >= this");
    cat.Get("box_ratio", c.box_ratio, "box if e2/e3 < this");
    cat.Get("flat_long_ratio", c.flat_long_ratio, "in between: flat if e1/e3 > this");
    cat.Get("boundary_softness", c.boundary_softness, "slope of the soft box/flat split");
    cat.Get("plate_thin_ratio", c.plate_thin_ratio, "thickness/diameter fully thin");
    cat.Get("plate_thick_ratio", c.plate_thick_ratio, "thickness/diameter not thin");
    cat.Get("plate_low_height", c.plate_low_height, "objects up to this high may be plates [m]");
    cat.Get("plate_high_height", c.plate_high_height, "objects from this high are no plates [m]");
    cat.Get("sphere_box_axis_area", c.sphere_box_axis_area,
            "sphere score fades from this axis_area");
    cat.Get("sphere_box_axis_area_max", c.sphere_box_axis_area_max, "... to 0 at this axis_area");
    cat.Get("round_fill", c.round_fill, "footprint fill up to this is round");
    cat.Get("square_fill", c.square_fill, "footprint fill from this is square");
    cat.Get("min_evidence", c.min_evidence, "other wins below this score");
    cat.Get("sharpness", c.sharpness, "exponent on scores before normalising");
    cat.Get("seed", c.seed, "RANSAC seed");

    auto box = config.Section("box");
    box.Get("inlier_threshold", p.box.inlier_threshold, "box surface inlier distance [m]");
    box.Get("use_normals", p.box.use_normals, "orient boxes by their side faces' normals");
    box.Get("face_angle_deg", p.box.face_angle_deg, "face point normal tolerance [deg]");
    box.Get("min_face_points", p.box.min_face_points, "points needed to place a face");

    auto cyl = config.Section("cylinder");
    auto& y = p.cylinder;
    cyl.Get("distance_threshold", y.sac.distance_threshold, "RANSAC inlier distance [m]");
    cyl.Get("max_iterations", y.sac.max_iterations, "RANSAC sample cap");
    cyl.Get("normal_distance_weight", y.sac.normal_distance_weight, "normal term weight");
    cyl.Get("seed", y.sac.seed, "RANSAC seed");
    cyl.Get("min_radius", y.min_radius, "smallest radius [m]");
    cyl.Get("max_radius", y.max_radius, "largest radius [m]");
    cyl.Get("upright_angle_deg", y.upright_angle_deg, "upright prior tolerance [deg]");
    cyl.Get("allow_free_axis", y.allow_free_axis, "also try a free axis");
    cyl.Get("free_axis_gain", y.free_axis_gain, "free axis must explain this factor more");
    cyl.Get("extend_to_support", y.extend_to_support, "upright cylinders reach the table");
    cyl.Get("cap_angle_deg", y.cap_angle_deg, "cap point normal tolerance [deg]");
    cyl.Get("min_cap_points", y.min_cap_points, "points needed to place a cap");
    cyl.Get("inlier_threshold", y.inlier_threshold, "surface distance for inlier_ratio [m]");

    auto models = config.Section("models");
    models.Get("min_inlier_ratio", p.min_model_inlier_ratio,
               "primitives explaining a smaller share of their points are replaced");
    models.Get("mesh_fallback", p.mesh_fallback,
               "replace rejected primitives by a triangulated mesh of the object's points");
    models.Get("mesh_search_radius", p.model_mesh.search_radius,
               "triangulation: longest edge and neighbourhood [m]");
    models.Get("mesh_mu", p.model_mesh.mu, "triangulation: neighbourhood / nearest distance");
    models.Get("mesh_max_surface_angle_deg", p.model_mesh.max_surface_angle_deg,
               "triangulation: largest angle between connected normals [deg]");
    models.Get("mesh_max_points", p.model_mesh_max_points,
               "triangulate at most this many points (even stride)");
    models.Get("min_attached_points", p.min_attached_points,
               "outliers of a kept primitive (a handle) are meshed and attached from this many, 0 "
               "= never");
    auto concentric = models.Section("concentric");
    concentric.Get("enabled", p.merge_concentric,
                   "merge objects whose cylinders share their axis (inside and outside of a pot)");
    concentric.Get("angle_deg", p.concentric_angle_deg, "axes parallel within [deg]");
    concentric.Get("distance", p.concentric_distance, "axis to axis at most [m]");
    concentric.Get("radius_ratio", p.concentric_radius_ratio,
                   "radii differ by at most this share of the larger one");
    models.Get("guided_fits", p.guided_fits,
               "box/cylinder fits sample by RSD and weight by part-graph part probabilities");
    models.Get("guided_rsd_radius", p.guided_rsd.radius, "RSD neighbourhood radius [m]");
    auto contained = models.Section("contained");
    contained.Get("enabled", p.merge_contained,
                  "join objects lying inside a container's cylinder or surface of revolution");
    contained.Get("margin", p.contained_margin, "the container's solid enlarged by this [m]");
    contained.Get("min_share", p.contained_min_share, "share of the object's points inside");
    auto stacked = models.Section("stacked");
    stacked.Get("enabled", p.split_stacked,
                "split box objects with two horizontal faces at different heights into two boxes");
    stacked.Get("min_face_points", p.stack_min_face_points, "points of each horizontal face");
    stacked.Get("min_step", p.stack_min_step, "height between the faces at least [m]");
    stacked.Get("min_gain", p.stack_min_gain,
                "two boxes must explain this much larger a share of the points than one");
    auto touching = models.Section("touching");
    touching.Get("enabled", p.split_touching,
                 "split box objects that one box explains poorly into two touching boxes");
    touching.Get("min_part_points", p.touching_min_part_points, "parts taking part in the splits");
    touching.Get("max_parts", p.touching_max_parts, "largest parts tried (2 to 12)");
    touching.Get("max_overlap", p.touching_max_overlap,
                 "the two solid boxes overlap by at most this share");
    touching.Get("min_gain", p.touching_min_gain,
                 "two boxes must explain this much larger a share of the points than one");
    touching.Get("max_points", p.touching_max_points, "points used per evaluation");
    touching.Get("round_enabled", p.split_touching_round,
                 "split round objects that one cylinder explains poorly into two cylinders");
    models.Get("several_min_ratio", p.several_min_ratio,
               "splits are tried when the part count is this much likelier for two objects");
    auto counts = models.Section("part_counts");
    counts.Get("flat_mean", p.part_counts.flat_mean, "Poisson mean of parts of flat objects");
    counts.Get("round_mean", p.part_counts.round_mean, "Poisson mean of parts of round objects");
    counts.Get("other_mean", p.part_counts.other_mean, "Poisson mean of parts of other objects");
    auto rot = models.Section("rotational");
    rot.Get("enabled", p.try_rotational,
            "surfaces of revolution for cylinder/sphere/other objects whose primitive fits poorly");
    rot.Get("max_tilt_deg", p.rotational.max_tilt_deg, "axis within this angle of up [deg]");
    rot.Get("max_points", p.rotational.max_points, "points used by the axis search");
    rot.Get("grid_directions", p.rotational.grid_directions, "coarse axis directions (sphere)");
    rot.Get("line_threshold", p.rotational.line_threshold, "normal line to axis distance [m]");
    rot.Get("profile_step", p.rotational.profile_step, "contour height bin [m]");
    rot.Get("inlier_threshold", p.rotational.inlier_threshold, "surface distance of an inlier [m]");
    rot.Get("profile_refinement", p.rotational.profile_refinement,
            "refine the axis by the thinnest contour and the level rim");
    auto ver = models.Section("verification");
    ver.Get("enabled", p.verify_models, "verify models against the frame's free space");
    ver.Get("voxel_size", p.verification.voxel_size, "occupancy cell [m]");
    ver.Get("margin", p.verification.margin, "grid margin around the model [m]");
    ver.Get("sample_spacing", p.verification.sample_spacing, "surface sample spacing [m]");
    ver.Get("tolerance_voxels", p.verification.tolerance_voxels,
            "occupied cells this close verify a sample [cells]");
    ver.Get("max_invalid_ratio", p.verification.max_invalid_ratio,
            "models with a larger share of surface in free space are rejected");
}

}  // namespace multicue
