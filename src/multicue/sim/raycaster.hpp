#pragma once
/// \file Ray casting against a scene with Embree 3: one BVH per distinct mesh, instanced with each
/// object's pose, so a scene of many copies of one mesh costs one BVH.

#include <cstdint>
#include <limits>
#include <memory>
#include <vector>

#include <Eigen/Core>

#include "multicue/sim/scene.hpp"

namespace multicue::sim {

/// The closest hit of a ray.
struct RayHit {
    float t = std::numeric_limits<float>::infinity();  ///< ray parameter (units of |dir|)
    std::uint32_t object = kNoObject;  ///< index into Scene::objects, kNoObject for a miss
    std::uint32_t triangle = 0;        ///< triangle of that object's mesh
    float u = 0.0f, v = 0.0f;          ///< barycentric coordinates of the hit in the triangle
    Eigen::Vector3f normal = Eigen::Vector3f::Zero();  ///< unit geometric normal, world frame,
                                                       ///< facing the ray origin

    static constexpr std::uint32_t kNoObject = 0xffffffffu;
    bool Valid() const { return object != kNoObject; }
};

/// A built BVH over a scene. Immutable after construction; Intersect/Occluded are thread-safe.
/// The scene must outlive the caster.
class RayCaster {
  public:
    /// Builds the BVH. Throws DataError for an object without a mesh or with a bad mesh.
    explicit RayCaster(const Scene& scene);
    ~RayCaster();
    RayCaster(const RayCaster&) = delete;
    RayCaster& operator=(const RayCaster&) = delete;

    /// Closest hit with t in [t_near, t_far].
    RayHit Intersect(const Eigen::Vector3f& origin, const Eigen::Vector3f& dir, float t_near = 0.0f,
                     float t_far = std::numeric_limits<float>::infinity()) const;
    /// True if anything is hit with t in [t_near, t_far].
    bool Occluded(const Eigen::Vector3f& origin, const Eigen::Vector3f& dir, float t_near,
                  float t_far) const;

    /// Closest hits of `n` rays from one origin (packets of 8: faster for coherent rays such as
    /// an image row). `hits` receives n entries, equal to what Intersect would give.
    void IntersectBatch(const Eigen::Vector3f& origin, const Eigen::Vector3f* dirs, std::size_t n,
                        float t_near, float t_far, RayHit* hits) const;
    /// Occlusion of `n` rays; rays with active[i] == false are skipped (occluded[i] = false) and
    /// their origins, directions and reaches never read.
    void OccludedBatch(const Eigen::Vector3f* origins, const Eigen::Vector3f* dirs,
                       const float* t_far, const bool* active, std::size_t n, float t_near,
                       bool* occluded) const;

    /// Colour at a hit: the object's colour or its mesh's interpolated vertex colour.
    Color HitColor(const RayHit& hit) const;
    /// Laser reflectance in [0, 1] at a hit: the mesh's interpolated vertex reflectance when it
    /// has one, else 0.1 + 0.8 * the luminance of HitColor.
    float HitReflectance(const RayHit& hit) const;
    /// Part index (into the hit object's PartMesh::part_names) of a hit.
    std::uint32_t HitPart(const RayHit& hit) const;

    const Scene& scene() const { return scene_; }

  private:
    struct Impl;
    const Scene& scene_;
    std::unique_ptr<Impl> impl_;
};

}  // namespace multicue::sim
