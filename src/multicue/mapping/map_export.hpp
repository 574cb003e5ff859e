#pragma once
/// \file Exports of a kitchen map (thesis section 4.1.3, Figures 4.7 and 4.8): JSON (everything
/// the map holds), URDF (the furniture as boxes, one link per door or drawer front with its joint,
/// handles as child links: the collision and articulation model of the kitchen) and OWL-DL in
/// RDF/XML in the style of KnowRob's semantic maps (instances with type, extents, pose,
/// articulation and the hierarchy kitchenette -> furniture -> fronts -> fixtures). Files are
/// written atomically.

#include <filesystem>
#include <string>

#include <nlohmann/json.hpp>

#include "multicue/io/urdf.hpp"
#include "multicue/mapping/semantic_map.hpp"

namespace multicue::mapping {

/// A right-handed rotation whose columns are the front's u axis, normal and v axis (the u axis
/// flipped where the three are left-handed): the front's orientation in the map exports.
Eigen::Matrix3f FrontRotation(const Front& f);

/// The map as JSON ("format": "multicue.kitchen-map/1"; docs/kitchens.md describes the keys).
nlohmann::ordered_json KitchenMapJson(const KitchenMap& map);

/// The map as a URDF model named `name`: a root link "kitchen_map", a box link per furniture
/// piece, worktop, table and wall, a link per front under its piece with its joint (revolute or
/// prismatic with the estimated axis and limits; fixed when unknown), a link per fixture under
/// its front.
io::UrdfModel KitchenMapUrdf(const KitchenMap& map, const std::string& name = "kitchen_map");

/// The map as OWL-DL (RDF/XML) with KnowRob's classes and properties; `name` becomes the
/// ontology IRI's last part.
std::string KitchenMapOwl(const KitchenMap& map, const std::string& name = "kitchen_map");

/// Writes map.json, map.urdf and map.owl into `dir` (created if missing), each atomically.
/// Throws IoError naming the path.
void WriteKitchenMap(const std::filesystem::path& dir, const KitchenMap& map,
                     const std::string& name = "kitchen_map");

}  // namespace multicue::mapping
