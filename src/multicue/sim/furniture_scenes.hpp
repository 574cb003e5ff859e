#pragma once
/// \file Scenes for the furniture detector (thesis sections 4.2.2 and 4.2.5): one piece of
/// furniture on the floor seen from sensor positions around it (the training views), and rooms
/// furnished as offices, seminar rooms or kitchens, scanned from several head positions.
///
/// Labels follow scene.hpp: 2 floor, 3 wall, 10*(k+1) object k. Furniture pieces carry their
/// category's index in CategoryNames(); distractors (bins, boxes, people) carry category 0.

#include <cstdint>
#include <functional>
#include <map>
#include <string>
#include <string_view>
#include <vector>

#include <Eigen/Geometry>

#include "multicue/sim/furniture_models.hpp"
#include "multicue/sim/scene.hpp"

namespace multicue::sim {

/// The floor (label 2) and `piece` (label 10) standing in its canonical frame at the origin,
/// turned by `yaw` about z.
Scene MakeFurnitureViewScene(const FurniturePiece& piece, float yaw = 0.0f);

struct FurnitureViewParams {
    int views = 16;               ///< sensor positions around the piece (thesis: 16), >= 1
    float min_distance = 1.5f;    ///< horizontal distance sensor - piece centre [m]
    float max_distance = 3.0f;    ///< [m], >= min_distance
    float sensor_height = 1.5f;   ///< above the floor [m], > 0
    float azimuth_jitter = 0.2f;  ///< random offset of each view's azimuth [rad], >= 0
    /// Throws InvalidArgument naming the first out-of-range field.
    void Validate() const;
};

/// Laser head poses (x forward, z up; see LaserParams) around the origin, view k at azimuth
/// 2 pi k / views plus jitter, at a random distance in [min, max], facing the origin.
std::vector<Eigen::Isometry3f> FurnitureViewHeads(const FurnitureViewParams& params,
                                                  std::uint64_t seed);
/// A camera pose (optical frame) at a head pose, looking at `target`.
Eigen::Isometry3f CameraAtHead(const Eigen::Isometry3f& head, const Eigen::Vector3f& target);

/// Furniture for rooms: pieces of a library half and procedural pieces.
class FurnitureSource {
  public:
    /// `library` pieces (any categories) and procedural pieces with probability
    /// `procedural_share` (always when the library has none of the category).
    FurnitureSource(std::vector<FurniturePiece> library, float procedural_share);
    /// A random piece of `category`; procedural ones get the id "procedural/<category>/<n>".
    FurniturePiece Random(const std::string& category, StreamRng& rng) const;
    bool HasLibrary(const std::string& category) const;

  private:
    std::map<std::string, std::vector<FurniturePiece>> pieces_;
    float procedural_share_ = 0.0f;
};

enum class RoomType {
    kOffice,   ///< desks with chairs, cabinets and sideboards along the walls
    kSeminar,  ///< rows of identical tables with identical chairs behind them
    kKitchen,  ///< cupboards along a wall, a dining table with chairs
};

/// "office", "seminar", "kitchen"; and back (InvalidArgument naming the choices).
const char* RoomTypeName(RoomType type);
RoomType ParseRoomType(std::string_view name);

struct FurnitureRoomParams {
    RoomType type = RoomType::kOffice;
    int max_distractors = 3;    ///< bins, boxes and people standing about, [0, max]
    float wall_height = 2.5f;   ///< [m]
    float min_gap = 0.05f;      ///< clearance between pieces that are not joined [m]
    /// Throws InvalidArgument naming the first out-of-range field.
    void Validate() const;
};

/// Ground truth of one piece of furniture in a room.
struct FurnitureTruth {
    std::uint32_t label = 0;   ///< its label in the scans
    std::string category;      ///< table, chair, cabinet or sideboard
    std::string id;            ///< FurniturePiece::id
    Eigen::Isometry3f T_world_object = Eigen::Isometry3f::Identity();  ///< canonical frame
    float yaw = 0.0f;          ///< rotation about z [rad]
    Eigen::Vector3f extent = Eigen::Vector3f::Zero();  ///< canonical box size [m]
    float width = 0.0f;        ///< FurnitureWidth [m]
};

struct FurnitureRoom {
    Scene scene;
    RoomType type = RoomType::kOffice;
    std::vector<FurnitureTruth> furniture;
    Eigen::Vector2f size = Eigen::Vector2f::Zero();  ///< floor x, y [m], centred on the origin
};

/// A furnished room of `params.type` from `source`. Pieces stand upright and never overlap
/// (joined tables touch); the layout, sizes and yaw angles are drawn from `seed`.
FurnitureRoom MakeFurnitureRoom(const FurnitureRoomParams& params, const FurnitureSource& source,
                                std::uint64_t seed);

/// `count` laser head poses `height` above the floor at free spots of the room (0.4 m from any
/// furniture, 0.5 m from the walls), spread over the room, facing its centre (x forward, z up).
std::vector<Eigen::Isometry3f> RoomHeadPoses(const FurnitureRoom& room, int count, float height,
                                             std::uint64_t seed);

}  // namespace multicue::sim
