#pragma once
/// \file URDF (Unified Robot Description Format) models: reading through urdfdom (Debian's
/// liburdfdom), writing through TinyXML, both into one plain value type. The kitchen simulator
/// reads PartNet-Mobility `mobility.urdf` files with it; kitchen maps are written as URDF with it
/// (one link per door or drawer front and its joint, thesis section 4.1.3).
///
/// PartNet-Mobility files give joint limits without the `effort` and `velocity` attributes that
/// URDF requires and urdfdom enforces; with UrdfReadParams::complete_limits (the default) the
/// reader adds `effort="0" velocity="0"` to such limits before urdfdom parses the file.

#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace multicue::io {

enum class UrdfJointType { kFixed, kRevolute, kContinuous, kPrismatic, kFloating, kPlanar };

/// "fixed", "revolute", "continuous", "prismatic", "floating" or "planar".
const char* UrdfJointTypeName(UrdfJointType type);

/// The shape of a visual or collision element.
struct UrdfGeometry {
    enum class Kind { kNone, kMesh, kBox, kCylinder, kSphere };
    Kind kind = Kind::kNone;
    std::string filename;                             ///< kMesh: as written in the file
    Eigen::Vector3d scale = Eigen::Vector3d::Ones();  ///< kMesh
    Eigen::Vector3d size = Eigen::Vector3d::Zero();   ///< kBox: full extents [m]
    double radius = 0.0;                              ///< kCylinder, kSphere [m]
    double length = 0.0;                              ///< kCylinder [m]
};

struct UrdfVisual {
    std::string name;                                          ///< empty when the file has none
    Eigen::Isometry3d origin = Eigen::Isometry3d::Identity();  ///< T_link_visual
    UrdfGeometry geometry;
    std::string material;                 ///< material name, empty for none
    std::optional<Eigen::Vector4d> rgba;  ///< material colour when given, in [0, 1]
};

struct UrdfLink {
    std::string name;
    std::vector<UrdfVisual> visuals;     ///< in file order
    std::vector<UrdfVisual> collisions;  ///< in file order
};

struct UrdfJoint {
    std::string name;
    UrdfJointType type = UrdfJointType::kFixed;
    std::string parent;                                        ///< parent link name
    std::string child;                                         ///< child link name
    Eigen::Isometry3d origin = Eigen::Isometry3d::Identity();  ///< T_parent_joint
    /// Joint axis in the joint frame, as written (not normalised; PartNet-Mobility has some of
    /// length 0.1). Unit X when the file gives none.
    Eigen::Vector3d axis = Eigen::Vector3d::UnitX();
    bool has_limits = false;
    double lower = 0.0;  ///< [rad] or [m]
    double upper = 0.0;  ///< [rad] or [m]
};

/// A whole model. Links and joints keep the file's order when read through ReadUrdf (urdfdom
/// itself keeps them in maps; the reader restores the order of the XML).
struct UrdfModel {
    std::string name;
    std::vector<UrdfLink> links;
    std::vector<UrdfJoint> joints;
    std::string root;  ///< the link that is no joint's child

    /// nullptr when absent.
    const UrdfLink* FindLink(const std::string& link_name) const;
    const UrdfJoint* FindJoint(const std::string& joint_name) const;
    /// The joint whose child is `link_name`; nullptr for the root.
    const UrdfJoint* ParentJoint(const std::string& link_name) const;
};

struct UrdfReadParams {
    /// Add effort="0" velocity="0" to <limit> elements that lack them (PartNet-Mobility files).
    bool complete_limits = true;
};

/// Parses URDF text with urdfdom. `source` names the text in error messages (a file name).
/// Throws FormatError naming `source` when the XML is malformed or urdfdom rejects the model
/// (urdfdom's own reason is logged at debug level).
UrdfModel ParseUrdf(const std::string& xml, const std::string& source,
                    const UrdfReadParams& params = {});

/// Reads a URDF file. Throws IoError (missing, unreadable) or FormatError, naming the file.
UrdfModel ReadUrdf(const std::filesystem::path& path, const UrdfReadParams& params = {});

/// The model as URDF text (XML with a declaration). Every joint of type revolute or prismatic is
/// written with its limits and effort="0" velocity="0". Throws InvalidArgument for a model that
/// is no tree: an empty or duplicate link or joint name, a joint naming a missing link, a link
/// with two parents, or not exactly one root.
std::string UrdfToXml(const UrdfModel& model);

/// Writes UrdfToXml(model) to `path` atomically. Throws as UrdfToXml, or IoError naming the path.
void WriteUrdf(const std::filesystem::path& path, const UrdfModel& model);

}  // namespace multicue::io
