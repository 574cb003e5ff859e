#pragma once
/// \file Where scene objects come from (procedural generators or a mesh library) and how they
/// rest on a support: stable poses and 2D footprints.

#include <cstddef>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "multicue/sim/mesh.hpp"
#include "multicue/sim/rng.hpp"

namespace multicue::sim {

/// An object ready to be placed: its mesh in metres (object frame), category and provenance.
struct ObjectModel {
    std::shared_ptr<const PartMesh> mesh;
    std::string category;  ///< CategoryNames() entry
    std::string source;    ///< mesh file name or procedural kind
    float scale = 1.0f;    ///< file units -> metres actually applied (1 for procedural)
    /// Inside of a container (procedural bowls and plates), upright in the object frame: points
    /// (r, z) of the inner wall from the inner floor (first point: floor edge radius and floor
    /// height) upwards, piecewise linear, never outside the mesh's wall. Empty: not a container.
    std::vector<Eigen::Vector2f> cavity{};
};

/// Which objects ObjectSource::RandomOf may return: procedural kinds (ProceduralKinds() names)
/// from a procedural source, mesh categories from a library. An empty list allows everything.
struct ObjectFilter {
    std::vector<std::string> kinds;
    std::vector<std::string> categories;
};

/// Draws objects: procedural (default) or from a mesh library. Library meshes are loaded once and
/// cached; meshes that fail to load are skipped with a warning (an error in strict mode).
/// Shrunk meshes (MeshEntry::rescale) get a random size in RealisticExtentRange(category).
class ObjectSource {
  public:
    /// Procedural objects of the given categories (default: all six table-top categories).
    explicit ObjectSource(std::vector<std::string> categories = {});
    /// Objects of a mesh library (ReadMeshLibrary).
    ObjectSource(std::vector<MeshEntry> library, bool strict);

    bool IsLibrary() const { return !library_.empty(); }
    const std::vector<MeshEntry>& library() const { return library_; }

    /// A random object. Throws DataError when no library mesh can be loaded.
    ObjectModel Random(StreamRng& rng);
    /// A random object that passes `filter` (Random when the list for this source is empty).
    /// Throws InvalidArgument for an unknown kind and DataError when no library mesh of the
    /// categories can be loaded.
    ObjectModel RandomOf(const ObjectFilter& filter, StreamRng& rng);
    /// Library entry i (random realistic size for shrunk meshes); nullopt if the mesh is bad and
    /// not strict.
    std::optional<ObjectModel> FromEntry(std::size_t i, StreamRng& rng);

  private:
    std::shared_ptr<const PartMesh> Load(std::size_t i);

    std::vector<std::string> categories_;
    std::vector<MeshEntry> library_;
    bool strict_ = false;
    std::map<std::size_t, std::shared_ptr<const PartMesh>> cache_;  ///< null: bad mesh
};

/// Rotations (object -> world, before yaw) under which the mesh rests stably on a horizontal
/// plane: candidate "down" directions are the object's +-x, +-y, +-z and +-principal axes; a
/// direction is stable when the projection of the surface centroid lies inside the convex hull of
/// the vertices within 0.5 mm of the lowest point, far enough that tipping over needs at least
/// 12 degrees (so no rolling cylinders, balls, or bottles on their caps). The first entry is the
/// upright pose (object -z down) when it is stable. Never empty: falls back to the upright pose.
std::vector<Eigen::Matrix3f> StableRotations(const PartMesh& mesh);

/// Convex hull (counter-clockwise) of 2D points (Andrew's monotone chain).
std::vector<Eigen::Vector2f> ConvexHull2D(std::vector<Eigen::Vector2f> points);

/// Separation of two convex polygons along the best separating axis (> 0: apart by at least that
/// much, <= 0: overlapping).
float PolygonSeparation(const std::vector<Eigen::Vector2f>& a,
                        const std::vector<Eigen::Vector2f>& b);

/// A random saturated colour.
Color RandomColor(StreamRng& rng);

}  // namespace multicue::sim
