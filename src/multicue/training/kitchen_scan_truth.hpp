#pragma once
/// \file The ground truth of a simulated kitchen scan (the fields sim::AddKitchenTruth writes)
/// read back per point, the true fronts it shows, and the matching of a kitchen map's fronts to
/// them. The container training labels furniture pieces with it; `kitchen_eval` scores with it.

#include <cstdint>
#include <map>
#include <utility>
#include <vector>

#include "multicue/core/point_cloud.hpp"
#include "multicue/mapping/kitchen_map.hpp"
#include "multicue/sim/kitchen_scene.hpp"

namespace multicue::training {

/// The ground-truth fields of a scan made by the kitchen simulator; a field the scan lacks reads
/// as zeros (no model, no link, no joint, class 0).
struct ScanTruth {
    std::vector<std::uint8_t> semantic;
    std::vector<std::uint16_t> model, link, joint;

    explicit ScanTruth(const PointCloud& scan);

    sim::KitchenClass Class(std::size_t i) const {
        return static_cast<sim::KitchenClass>(semantic[i]);
    }
    bool IsFront(std::size_t i) const {
        return Class(i) == sim::KitchenClass::kDoor || Class(i) == sim::KitchenClass::kDrawer;
    }
    /// Key of a point's (instance, link): (model << 16) | link, 0 for none.
    std::uint32_t Key(std::size_t i) const {
        return model[i] == 0 ? 0u : (std::uint32_t{model[i]} << 16) | link[i];
    }
};

/// A true front: the door or drawer points of one (instance, link) in a scan.
struct TrueFront {
    std::uint32_t key = 0;
    std::size_t points = 0;
    std::size_t fixture_points = 0;  ///< visible handle or knob points of the same link
    int joint = -1;                  ///< index into the kitchen's joints, -1 for none
};

/// The fronts a scan shows, by key (ScanTruth::Key), with the joint most of their points move by.
std::map<std::uint32_t, TrueFront> TrueFronts(const PointCloud& scan, const ScanTruth& truth);

/// Matches a map's fronts to true fronts greedily by IoU of their points (front indices minus
/// `offset` index the scan); returns per true front key the matched front's index and the IoU.
/// Fronts without a match are absent.
std::map<std::uint32_t, std::pair<int, float>> MatchFronts(
    const mapping::KitchenMap& map, const ScanTruth& truth,
    const std::map<std::uint32_t, TrueFront>& fronts, std::size_t offset = 0);

/// The kitchen instance (index into KitchenScene::instances) each furniture piece of `map`
/// belongs to: the one whose fronts, matched with IoU >= `min_iou`, hold most of the piece's
/// matched points. Pieces without a matched front, and fronts of no piece, are absent.
std::map<int, int> FurnitureInstances(const mapping::KitchenMap& map, const PointCloud& scan,
                                      float min_iou = 0.3f);

/// The key of `votes` with the largest count (the first in key order on ties); -1 when no count
/// is above zero.
int MostVoted(const std::map<int, std::size_t>& votes);

}  // namespace multicue::training
