#pragma once
/// \file Articulated models for the simulator: PartNet-Mobility folders (mobility.urdf,
/// semantics.txt, textured OBJ parts) loaded through their URDF (io::ReadUrdf, urdfdom), one
/// PartMesh per link in metres with the colours of the parts' materials and textures, and forward
/// kinematics for any joint state (doors and drawers closed or opened).
///
/// Model frame (after LoadArticulatedModel): z up, the front (the side doors and drawers open
/// towards) facing +x, the bounding box of the closed model centred on x = y = 0 with its bottom
/// at z = 0. PartNet-Mobility files are y-up in the mesh frame; their URDF's fixed base joint turns
/// them z-up, and the loader then turns the model about z so that its fronts face +x, found from
/// the way its doors and drawers move when opened.

#include <cstdint>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "multicue/io/urdf.hpp"
#include "multicue/sim/mesh.hpp"

namespace multicue::sim {

/// One link: its mesh in the link frame (parts named after the URDF visuals without their
/// numeric suffix: "handle", "cabinet_door_surface", "knob", ...) and its semantics.txt entry.
struct ArticulatedLink {
    std::string name;                      ///< URDF link name ("link_0")
    std::string joint_kind;                ///< semantics.txt: hinge, slider, heavy, static, free
    std::string semantic;                  ///< semantics.txt part: rotation_door, drawer, ...
    std::shared_ptr<const PartMesh> mesh;  ///< in the link frame [m]; null for a link without
                                           ///< visuals
    int parent_joint = -1;                 ///< joint whose child this is; -1 for the root
};

struct ArticulatedJoint {
    std::string name;
    io::UrdfJointType type = io::UrdfJointType::kFixed;
    int parent = -1;                                                   ///< parent link index
    int child = -1;                                                    ///< child link index
    Eigen::Isometry3f T_parent_joint = Eigen::Isometry3f::Identity();  ///< [m]
    Eigen::Vector3f axis = Eigen::Vector3f::UnitX();  ///< unit axis in the joint frame
    float lower = 0.0f;                               ///< [rad] or [m]; 0 for joints without limits
    float upper = 0.0f;                               ///< [rad] or [m]

    bool Movable() const {
        return type == io::UrdfJointType::kRevolute || type == io::UrdfJointType::kPrismatic ||
               type == io::UrdfJointType::kContinuous;
    }
    /// Joint value of the closed state: 0 clamped into [lower, upper].
    float Closed() const;
    /// Joint value `fraction` of the way from Closed() to the limit farther from it (continuous
    /// joints: fraction * 2 pi).
    float Opened(float fraction) const;
};

struct ArticulatedModel {
    std::string id;      ///< folder relative to the library ("CabinetLower/45213")
    std::string kind;    ///< labels.csv kind (cupboard, fridge, ...); empty if unknown
    float scale = 1.0f;  ///< file units -> metres
    std::vector<ArticulatedLink> links;
    std::vector<ArticulatedJoint> joints;
    int root = 0;  ///< root link index
    /// Model frame from the URDF's root link frame (see the file comment) [m].
    Eigen::Isometry3f T_model_root = Eigen::Isometry3f::Identity();
    /// Bounds of the closed model in the model frame [m].
    Eigen::AlignedBox3f bounds;

    /// Joint values with every joint closed.
    std::vector<float> ClosedState() const;
    /// T_model_link of every link for joint values `q` (one per joint; fixed joints ignore theirs).
    /// Throws InvalidArgument when q has the wrong size.
    std::vector<Eigen::Isometry3f> LinkPoses(const std::vector<float>& q) const;
    /// Index of a link by name; -1 if absent.
    int FindLink(const std::string& name) const;
};

struct ArticulatedLoadParams {
    float scale = 1.0f;  ///< file units -> metres (labels.csv scale_to_m)
    /// Textures are averaged down to this many pixels a side before the parts' vertices take
    /// their colour from them: the simulator wants the colour of a surface, not its grain [px].
    std::uint32_t texture_size = 16;
    /// Refuse a model whose URDF names a missing part mesh; false loads it without those parts
    /// (logged at info level): one PartNet-Mobility microwave lacks its buttons' meshes.
    bool strict = false;
};

/// Loads a PartNet-Mobility folder. Visual meshes are read with Assimp, scaled and placed by the
/// visual origins; each vertex gets its material's diffuse colour times the texture colour at its
/// texture coordinate (PNG and JPEG textures, io::ReadRgbImage) and a reflectance for the laser's
/// intensity (the colour's luminance, lowered for specular and transparent materials). Links
/// without a semantics.txt line get joint_kind and semantic "unknown".
/// Throws IoError / FormatError naming the file (missing or malformed mobility.urdf, semantics.txt
/// or a part mesh), DataError for a model without any geometry, InvalidArgument for a bad scale.
ArticulatedModel LoadArticulatedModel(const std::filesystem::path& folder,
                                      const ArticulatedLoadParams& params = {});

}  // namespace multicue::sim
