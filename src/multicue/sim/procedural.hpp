#pragma once
/// \file Procedural household objects for the categories of the perceive contract (sphere, box,
/// flat, cylinder, plate, other; Table 5.1): boxes, flat boxes, cans, cups, mugs with handles,
/// bottles, balls, bowls, plates, pitchers and irregular blobs, with random dimensions in
/// realistic ranges (docs/simulation.md lists them) and named parts ("body", "handle", ...).
/// Meshes are in the object frame: z up, resting upright on z = 0, centred on the z axis.

#include <string>
#include <vector>

#include <Eigen/Core>

#include "multicue/sim/mesh.hpp"
#include "multicue/sim/rng.hpp"

namespace multicue::sim {

struct ProceduralObject {
    PartMesh mesh;         ///< mesh.name is the kind
    std::string category;  ///< one of TabletopCategories()
    std::string kind;      ///< "box", "mug", ... (ProceduralKinds())
    /// Inner wall (r, z) of a container ("bowl", "plate"), as ObjectModel::cavity; else empty.
    std::vector<Eigen::Vector2f> cavity{};
};

/// Every kind of procedural object and its category.
const std::vector<std::pair<std::string, std::string>>& ProceduralKinds();

/// A random object of `category` (a random kind of that category). Throws InvalidArgument for an
/// unknown category.
ProceduralObject MakeProceduralObject(const std::string& category, StreamRng& rng);
/// A random object of one kind ("ball", "bowl", "box", "flat_box", "can", "cup", "mug", "tin",
/// "bottle", "plate", "pitcher", "irregular"). Throws InvalidArgument for an unknown kind.
ProceduralObject MakeProceduralKind(const std::string& kind, StreamRng& rng);

/// An axis-aligned box with its base centred at the origin on z = 0; one part `part`.
PartMesh MakeBoxMesh(const Eigen::Vector3f& extents, const std::string& part = "body");

/// One point of a revolution profile: radius r and height z [m]; the segment from this point to
/// the next belongs to part `part` (index into the part list given to MakeRevolutionMesh).
struct ProfilePoint {
    float r = 0.0f;
    float z = 0.0f;
    std::uint32_t part = 0;
};
/// Surface of revolution of `profile` about the z axis with `segments` sectors; profile points
/// with r == 0 become single pole vertices.
PartMesh MakeRevolutionMesh(const std::vector<ProfilePoint>& profile,
                            const std::vector<std::string>& parts, int segments = 48);

}  // namespace multicue::sim
