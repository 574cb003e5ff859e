#include "multicue/sim/raycaster.hpp"

#include <algorithm>
#include <cstdlib>
#include <map>
#include <mutex>
#include <string>

#include <embree3/rtcore.h>
#include <fmt/format.h>

#include "multicue/core/exceptions.hpp"

namespace multicue::sim {
namespace {

/// One Embree device for the process: creating one per scene costs thread start-up. Its
/// configuration string gets MULTICUE_EMBREE_CONFIG appended when that is set (Embree picks its
/// kernels by the CPU's instruction set, and they round differently: "isa=avx2" on two machines
/// gives both the same kernels).
RTCDevice SharedDevice() {
    static RTCDevice device = [] {
        std::string config = "verbose=0";
        if (const char* extra = std::getenv("MULTICUE_EMBREE_CONFIG"); extra && *extra) {
            config += std::string(",") + extra;
        }
        RTCDevice d = rtcNewDevice(config.c_str());
        if (d == nullptr) {
            throw Error(
                fmt::format("cannot create an Embree device (configuration \"{}\")", config));
        }
        return d;
    }();
    return device;
}

}  // namespace

struct RayCaster::Impl {
    RTCScene top = nullptr;
    std::vector<RTCScene> mesh_scenes;
    /// Per object: triangle normals in the object frame (shared per mesh) and the world rotation.
    std::vector<const std::vector<Eigen::Vector3f>*> normals;
    std::vector<Eigen::Matrix3f> rotations;
    std::map<const PartMesh*, std::vector<Eigen::Vector3f>> normal_store;

    ~Impl() {
        if (top != nullptr) rtcReleaseScene(top);
        for (auto s : mesh_scenes) rtcReleaseScene(s);
    }
};

RayCaster::RayCaster(const Scene& scene) : scene_(scene), impl_(std::make_unique<Impl>()) {
    RTCDevice device = SharedDevice();
    impl_->top = rtcNewScene(device);
    std::map<const PartMesh*, RTCScene> built;
    for (std::size_t i = 0; i < scene.objects.size(); ++i) {
        const SceneObject& obj = scene.objects[i];
        if (!obj.mesh || obj.mesh->mesh.triangles.empty()) {
            throw DataError(fmt::format("scene object {} has no mesh", i));
        }
        const PartMesh* pm = obj.mesh.get();
        auto it = built.find(pm);
        if (it == built.end()) {
            pm->mesh.Validate();
            RTCScene s = rtcNewScene(device);
            RTCGeometry g = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_TRIANGLE);
            const auto& V = pm->mesh.vertices;
            const auto& T = pm->mesh.triangles;
            auto* vb = static_cast<float*>(rtcSetNewGeometryBuffer(
                g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, 3 * sizeof(float), V.size()));
            for (std::size_t k = 0; k < V.size(); ++k) {
                vb[3 * k] = V[k].x();
                vb[3 * k + 1] = V[k].y();
                vb[3 * k + 2] = V[k].z();
            }
            auto* ib = static_cast<unsigned*>(rtcSetNewGeometryBuffer(
                g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, 3 * sizeof(unsigned), T.size()));
            for (std::size_t k = 0; k < T.size(); ++k) {
                for (int c = 0; c < 3; ++c) ib[3 * k + c] = T[k][c];
            }
            rtcCommitGeometry(g);
            rtcAttachGeometryByID(s, g, 0);
            rtcReleaseGeometry(g);
            rtcCommitScene(s);
            impl_->mesh_scenes.push_back(s);
            it = built.emplace(pm, s).first;
            impl_->normal_store.emplace(pm, pm->mesh.ComputeTriangleNormals());
        }
        RTCGeometry inst = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_INSTANCE);
        rtcSetGeometryInstancedScene(inst, it->second);
        const Eigen::Matrix<float, 3, 4> xfm = obj.T_world_object.matrix().topRows<3>();
        rtcSetGeometryTransform(inst, 0, RTC_FORMAT_FLOAT3X4_COLUMN_MAJOR, xfm.data());
        rtcCommitGeometry(inst);
        rtcAttachGeometryByID(impl_->top, inst, static_cast<unsigned>(i));
        rtcReleaseGeometry(inst);
        impl_->normals.push_back(&impl_->normal_store.at(pm));
        impl_->rotations.push_back(obj.T_world_object.linear());
    }
    rtcCommitScene(impl_->top);
}

RayCaster::~RayCaster() = default;

RayHit RayCaster::Intersect(const Eigen::Vector3f& origin, const Eigen::Vector3f& dir, float t_near,
                            float t_far) const {
    RTCIntersectContext context;
    rtcInitIntersectContext(&context);
    RTCRayHit rh;
    rh.ray.org_x = origin.x();
    rh.ray.org_y = origin.y();
    rh.ray.org_z = origin.z();
    rh.ray.dir_x = dir.x();
    rh.ray.dir_y = dir.y();
    rh.ray.dir_z = dir.z();
    rh.ray.tnear = t_near;
    rh.ray.tfar = t_far;
    rh.ray.time = 0.0f;
    rh.ray.mask = 0xffffffffu;
    rh.ray.id = 0;
    rh.ray.flags = 0;
    rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
    rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
    rtcIntersect1(impl_->top, &context, &rh);
    RayHit hit;
    if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) return hit;
    hit.object = rh.hit.instID[0];
    hit.triangle = rh.hit.primID;
    hit.t = rh.ray.tfar;
    hit.u = rh.hit.u;
    hit.v = rh.hit.v;
    Eigen::Vector3f n = impl_->rotations[hit.object] * (*impl_->normals[hit.object])[hit.triangle];
    if (n.dot(dir) > 0.0f) n = -n;
    hit.normal = n;
    return hit;
}

bool RayCaster::Occluded(const Eigen::Vector3f& origin, const Eigen::Vector3f& dir, float t_near,
                         float t_far) const {
    RTCIntersectContext context;
    rtcInitIntersectContext(&context);
    RTCRay ray;
    ray.org_x = origin.x();
    ray.org_y = origin.y();
    ray.org_z = origin.z();
    ray.dir_x = dir.x();
    ray.dir_y = dir.y();
    ray.dir_z = dir.z();
    ray.tnear = t_near;
    ray.tfar = t_far;
    ray.time = 0.0f;
    ray.mask = 0xffffffffu;
    ray.id = 0;
    ray.flags = 0;
    rtcOccluded1(impl_->top, &context, &ray);
    return ray.tfar < 0.0f;  // Embree sets tfar to -inf on a hit
}

void RayCaster::IntersectBatch(const Eigen::Vector3f& origin, const Eigen::Vector3f* dirs,
                               std::size_t n, float t_near, float t_far, RayHit* hits) const {
    for (std::size_t b = 0; b < n; b += 8) {
        const std::size_t m = std::min<std::size_t>(8, n - b);
        alignas(32) int valid[8];
        alignas(32) RTCRayHit8 rh;
        for (std::size_t k = 0; k < 8; ++k) {
            const bool on = k < m;
            valid[k] = on ? -1 : 0;
            const Eigen::Vector3f& d = dirs[b + (on ? k : 0)];
            rh.ray.org_x[k] = origin.x();
            rh.ray.org_y[k] = origin.y();
            rh.ray.org_z[k] = origin.z();
            rh.ray.dir_x[k] = d.x();
            rh.ray.dir_y[k] = d.y();
            rh.ray.dir_z[k] = d.z();
            rh.ray.tnear[k] = t_near;
            // A lane past the end ends before it starts (see OccludedBatch).
            rh.ray.tfar[k] = on ? t_far : std::min(t_near, 0.0f) - 1.0f;
            rh.ray.time[k] = 0.0f;
            rh.ray.mask[k] = 0xffffffffu;
            rh.ray.id[k] = static_cast<unsigned>(k);
            rh.ray.flags[k] = 0;
            rh.hit.geomID[k] = RTC_INVALID_GEOMETRY_ID;
            rh.hit.instID[0][k] = RTC_INVALID_GEOMETRY_ID;
        }
        RTCIntersectContext context;
        rtcInitIntersectContext(&context);
        rtcIntersect8(valid, impl_->top, &context, &rh);
        for (std::size_t k = 0; k < m; ++k) {
            RayHit& hit = hits[b + k];
            hit = RayHit{};
            if (rh.hit.geomID[k] == RTC_INVALID_GEOMETRY_ID) continue;
            hit.object = rh.hit.instID[0][k];
            hit.triangle = rh.hit.primID[k];
            hit.t = rh.ray.tfar[k];
            hit.u = rh.hit.u[k];
            hit.v = rh.hit.v[k];
            Eigen::Vector3f nrm =
                impl_->rotations[hit.object] * (*impl_->normals[hit.object])[hit.triangle];
            if (nrm.dot(dirs[b + k]) > 0.0f) nrm = -nrm;
            hit.normal = nrm;
        }
    }
}

void RayCaster::OccludedBatch(const Eigen::Vector3f* origins, const Eigen::Vector3f* dirs,
                              const float* t_far, const bool* active, std::size_t n, float t_near,
                              bool* occluded) const {
    for (std::size_t b = 0; b < n; b += 8) {
        const std::size_t m = std::min<std::size_t>(8, n - b);
        alignas(32) int valid[8];
        alignas(32) RTCRay8 ray;
        bool any = false;
        for (std::size_t k = 0; k < 8; ++k) {
            const bool on = k < m && active[b + k];
            any = any || on;
            valid[k] = on ? -1 : 0;
            // An inactive lane's data may be anything (the caller fills active rays only).
            // Embree gets a finite ray there that ends before it starts: a device without
            // 8-wide kernels traces a packet as a stream, which skips such rays only and
            // ignores `valid`.
            const Eigen::Vector3f org = on ? origins[b + k] : Eigen::Vector3f::Zero();
            const Eigen::Vector3f dir = on ? dirs[b + k] : Eigen::Vector3f::UnitZ();
            ray.org_x[k] = org.x();
            ray.org_y[k] = org.y();
            ray.org_z[k] = org.z();
            ray.dir_x[k] = dir.x();
            ray.dir_y[k] = dir.y();
            ray.dir_z[k] = dir.z();
            ray.tnear[k] = t_near;
            ray.tfar[k] = on ? t_far[b + k] : std::min(t_near, 0.0f) - 1.0f;
            ray.time[k] = 0.0f;
            ray.mask[k] = 0xffffffffu;
            ray.id[k] = static_cast<unsigned>(k);
            ray.flags[k] = 0;
        }
        if (any) {
            RTCIntersectContext context;
            rtcInitIntersectContext(&context);
            rtcOccluded8(valid, impl_->top, &context, &ray);
        }
        for (std::size_t k = 0; k < m; ++k) {
            occluded[b + k] = any && valid[k] != 0 && ray.tfar[k] < 0.0f;
        }
    }
}

Color RayCaster::HitColor(const RayHit& hit) const {
    const SceneObject& obj = scene_.objects[hit.object];
    if (!obj.use_vertex_colors || !obj.mesh->mesh.HasVertexColors()) return obj.color;
    const auto& tri = obj.mesh->mesh.triangles[hit.triangle];
    const auto& C = obj.mesh->mesh.vertex_colors;
    const float w0 = 1.0f - hit.u - hit.v;
    auto mix = [&](auto member) {
        const float v = w0 * static_cast<float>(C[tri[0]].*member) +
                        hit.u * static_cast<float>(C[tri[1]].*member) +
                        hit.v * static_cast<float>(C[tri[2]].*member);
        return static_cast<std::uint8_t>(std::clamp(v + 0.5f, 0.0f, 255.0f));
    };
    return Color{mix(&Color::r), mix(&Color::g), mix(&Color::b), 255};
}

float RayCaster::HitReflectance(const RayHit& hit) const {
    const PartMesh& mesh = *scene_.objects[hit.object].mesh;
    if (mesh.vertex_reflectance.size() == mesh.mesh.vertices.size() && !mesh.mesh.empty()) {
        const auto& tri = mesh.mesh.triangles[hit.triangle];
        const auto& R = mesh.vertex_reflectance;
        return std::clamp(
            (1.0f - hit.u - hit.v) * R[tri[0]] + hit.u * R[tri[1]] + hit.v * R[tri[2]], 0.0f, 1.0f);
    }
    const Color c = HitColor(hit);
    return 0.1f + 0.8f * (0.299f * c.r + 0.587f * c.g + 0.114f * c.b) / 255.0f;
}

std::uint32_t RayCaster::HitPart(const RayHit& hit) const {
    const auto& parts = scene_.objects[hit.object].mesh->triangle_parts;
    return hit.triangle < parts.size() ? parts[hit.triangle] : 0u;
}

}  // namespace multicue::sim
