// The configuration of the table-top pipeline. Every parameter struct lists its own parameters
// (VisitParams: key = the field's name, field, meaning); the same rows read a file, print the
// defaults (`multicue config --dump`) and the parameter reference (`--markdown`). What is left
// here are the keys of earlier releases.

#include <string>
#include <utility>
#include <vector>

#include "multicue/system/perceive.hpp"

namespace multicue {

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
    // The rules' keys sat directly in "category"; read them off the rules' own table.
    io::ConfigSection rules = io::ConfigSection::Dump();
    CategoryParams defaults;
    defaults.VisitParams(rules);
    for (const auto& key : rules.RecordedKeys()) {
        renamed.emplace_back("category." + key, "category.rules." + key);
    }
    return renamed;
}

void ReadPerceiveParams(io::ConfigSection& config, PerceiveParams& params) {
    for (const auto& [from, to] : PerceiveRenamedKeys()) config.Rename(from, to);
    params.VisitParams(config);
}

}  // namespace multicue
