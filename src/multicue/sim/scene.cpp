#include "multicue/sim/scene.hpp"

#include <cmath>

#include "multicue/core/exceptions.hpp"

namespace multicue::sim {

const char* ObjectPlacementName(ObjectPlacement placement) {
    switch (placement) {
        case ObjectPlacement::kStanding:
            return "standing";
        case ObjectPlacement::kTouching:
            return "touching";
        case ObjectPlacement::kStacked:
            return "stacked";
        case ObjectPlacement::kNested:
            return "nested";
        case ObjectPlacement::kLeaning:
            return "leaning";
        case ObjectPlacement::kFixed:
            break;
    }
    return "fixed";
}

std::size_t Scene::NumObjects() const {
    std::size_t n = 0;
    for (const auto& o : objects) n += o.label >= ObjectLabel(1) ? 1 : 0;
    return n;
}

int FindObject(const Scene& scene, std::uint32_t label) {
    for (std::size_t i = 0; i < scene.objects.size(); ++i) {
        if (scene.objects[i].label == label) return static_cast<int>(i);
    }
    return -1;
}

Eigen::Isometry3f LookAt(const Eigen::Vector3f& eye, const Eigen::Vector3f& target) {
    const Eigen::Vector3f f = target - eye;
    if (!(f.norm() > 1e-6f)) throw InvalidArgument("look-at: eye and target coincide");
    const Eigen::Vector3f z = f.normalized();
    const Eigen::Vector3f right = z.cross(Eigen::Vector3f::UnitZ());
    if (right.norm() < 1e-4f) throw InvalidArgument("look-at: looking straight up or down");
    const Eigen::Vector3f x = right.normalized();
    const Eigen::Vector3f y = z.cross(x);  // image down
    Eigen::Isometry3f T = Eigen::Isometry3f::Identity();
    T.linear().col(0) = x;
    T.linear().col(1) = y;
    T.linear().col(2) = z;
    T.translation() = eye;
    return T;
}

}  // namespace multicue::sim
