#include "multicue/sim/articulated.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <fstream>
#include <map>
#include <numbers>
#include <sstream>

#include <assimp/material.h>
#include <assimp/postprocess.h>
#include <assimp/scene.h>
#include <fmt/format.h>
#include <assimp/Importer.hpp>

#include "multicue/core/exceptions.hpp"
#include "multicue/core/logging.hpp"
#include "multicue/io/image.hpp"
#include "multicue/sim/assimp_read.hpp"

namespace multicue::sim {
namespace {

/// "handle-6" -> "handle"; names without a numeric suffix stay as they are.
std::string PartName(const std::string& visual) {
    const auto dash = visual.rfind('-');
    if (dash == std::string::npos || dash + 1 == visual.size()) {
        return visual.empty() ? "part" : visual;
    }
    for (std::size_t i = dash + 1; i < visual.size(); ++i) {
        if (!std::isdigit(static_cast<unsigned char>(visual[i]))) return visual;
    }
    return visual.substr(0, dash);
}

/// Textures of one model, read once and shrunk.
class TextureCache {
  public:
    explicit TextureCache(std::uint32_t size) : size_(size) {}
    const io::RgbImage* Get(const std::filesystem::path& path) {
        const std::string key = path.lexically_normal().string();
        auto it = images_.find(key);
        if (it == images_.end()) {
            io::RgbImage img;
            try {
                img = io::ShrinkImage(io::ReadRgbImage(path), size_);
            } catch (const Error& e) {
                LogWarning("texture ignored: {}", e.what());
            }
            it = images_.emplace(key, std::move(img)).first;
        }
        return it->second.empty() ? nullptr : &it->second;
    }

  private:
    std::uint32_t size_;
    std::map<std::string, io::RgbImage> images_;
};

/// Bilinear texture lookup with wrap-around (OBJ texture coordinates repeat), v up.
Eigen::Vector3f Sample(const io::RgbImage& img, float u, float v) {
    const float x = (u - std::floor(u)) * static_cast<float>(img.width) - 0.5f;
    const float y = (1.0f - (v - std::floor(v))) * static_cast<float>(img.height) - 0.5f;
    const int x0 = static_cast<int>(std::floor(x)), y0 = static_cast<int>(std::floor(y));
    const float fx = x - static_cast<float>(x0), fy = y - static_cast<float>(y0);
    auto at = [&](int xi, int yi) {
        const auto w = static_cast<int>(img.width), h = static_cast<int>(img.height);
        xi = ((xi % w) + w) % w;
        yi = ((yi % h) + h) % h;
        const Color& c = img.At(static_cast<std::uint32_t>(xi), static_cast<std::uint32_t>(yi));
        return Eigen::Vector3f(c.r, c.g, c.b);
    };
    return (1 - fy) * ((1 - fx) * at(x0, y0) + fx * at(x0 + 1, y0)) +
           fy * ((1 - fx) * at(x0, y0 + 1) + fx * at(x0 + 1, y0 + 1));
}

/// Appearance of one Assimp material: diffuse colour, texture, reflectance factor.
struct Material {
    Eigen::Vector3f diffuse = Eigen::Vector3f::Ones();  ///< [0, 1]
    const io::RgbImage* texture = nullptr;
    float reflectance_factor = 1.0f;  ///< < 1 for specular or transparent materials
};

Material ReadMaterial(const aiMaterial* m, const std::filesystem::path& dir, TextureCache& cache) {
    Material out;
    if (m == nullptr) return out;
    aiColor3D kd(1, 1, 1), ks(0, 0, 0);
    float opacity = 1.0f;
    m->Get(AI_MATKEY_COLOR_DIFFUSE, kd);
    m->Get(AI_MATKEY_COLOR_SPECULAR, ks);
    m->Get(AI_MATKEY_OPACITY, opacity);
    out.diffuse = Eigen::Vector3f(kd.r, kd.g, kd.b).cwiseMax(0.0f).cwiseMin(1.0f);
    aiString tex;
    if (m->GetTexture(aiTextureType_DIFFUSE, 0, &tex) == AI_SUCCESS && tex.length > 0) {
        out.texture = cache.Get(dir / tex.C_Str());
    }
    // A laser returns less from mirror-like and see-through surfaces (metal, glass).
    const float specular = std::clamp((ks.r + ks.g + ks.b) / 3.0f, 0.0f, 1.0f);
    out.reflectance_factor =
        std::clamp(1.0f - 0.6f * specular, 0.2f, 1.0f) * std::clamp(opacity, 0.2f, 1.0f);
    return out;
}

/// Appends the triangles of one visual's mesh file to `out` as part `part`, transformed by
/// `T` (visual origin, scale included), with colours and reflectance.
void AppendVisual(const std::filesystem::path& file, const Eigen::Affine3f& T,
                  const std::string& part, TextureCache& cache, PartMesh& out,
                  std::vector<float>& reflectance) {
    Assimp::Importer importer;
    const aiScene* scene =
        assimp_read::ReadScene(importer, file, aiProcess_Triangulate | aiProcess_SortByPType);
    std::uint32_t part_index = 0;
    const auto it = std::find(out.part_names.begin(), out.part_names.end(), part);
    if (it == out.part_names.end()) {
        out.part_names.push_back(part);
        part_index = static_cast<std::uint32_t>(out.part_names.size() - 1);
    } else {
        part_index = static_cast<std::uint32_t>(it - out.part_names.begin());
    }
    const std::filesystem::path dir = file.parent_path();
    // OBJ files carry no node transforms worth keeping (Assimp puts every group at identity).
    for (unsigned k = 0; k < scene->mNumMeshes; ++k) {
        const aiMesh* mesh = scene->mMeshes[k];
        const Material mat = ReadMaterial(scene->mMaterials[mesh->mMaterialIndex], dir, cache);
        const auto base = static_cast<std::uint32_t>(out.mesh.vertices.size());
        const bool uv = mesh->HasTextureCoords(0) && mat.texture != nullptr;
        for (unsigned i = 0; i < mesh->mNumVertices; ++i) {
            const aiVector3D& p = mesh->mVertices[i];
            out.mesh.vertices.push_back(T * Eigen::Vector3f(p.x, p.y, p.z));
            Eigen::Vector3f rgb = mat.diffuse * 255.0f;
            if (uv) {
                const aiVector3D& t = mesh->mTextureCoords[0][i];
                rgb = rgb.cwiseProduct(Sample(*mat.texture, t.x, t.y)) / 255.0f;
            } else if (mat.texture != nullptr) {
                rgb = rgb.cwiseProduct(Sample(*mat.texture, 0.5f, 0.5f)) / 255.0f;
            }
            rgb = rgb.cwiseMax(0.0f).cwiseMin(255.0f);
            out.mesh.vertex_colors.push_back(Color{static_cast<std::uint8_t>(rgb.x() + 0.5f),
                                                   static_cast<std::uint8_t>(rgb.y() + 0.5f),
                                                   static_cast<std::uint8_t>(rgb.z() + 0.5f), 255});
            const float lum = (0.299f * rgb.x() + 0.587f * rgb.y() + 0.114f * rgb.z()) / 255.0f;
            reflectance.push_back((0.1f + 0.8f * lum) * mat.reflectance_factor);
        }
        for (unsigned f = 0; f < mesh->mNumFaces; ++f) {
            const aiFace& face = mesh->mFaces[f];
            if (face.mNumIndices != 3) continue;
            out.mesh.triangles.emplace_back(base + face.mIndices[0], base + face.mIndices[1],
                                            base + face.mIndices[2]);
            out.triangle_parts.push_back(part_index);
        }
    }
}

/// semantics.txt: "link_k <joint kind> <part>" per line.
std::map<std::string, std::pair<std::string, std::string>> ReadSemantics(
    const std::filesystem::path& path) {
    std::map<std::string, std::pair<std::string, std::string>> out;
    std::ifstream in(path);
    if (!in) throw IoError(fmt::format("{}: cannot open", path.string()));
    std::string line;
    int number = 0;
    while (std::getline(in, line)) {
        ++number;
        std::istringstream ls(line);
        std::string link, kind, part;
        if (!(ls >> link)) continue;
        if (!(ls >> kind >> part)) {
            throw FormatError(
                fmt::format("{}:{}: expected 'link kind part'", path.string(), number));
        }
        out[link] = {kind, part};
    }
    return out;
}

Eigen::Isometry3f ToFloat(const Eigen::Isometry3d& T, float scale) {
    Eigen::Isometry3f out = Eigen::Isometry3f::Identity();
    out.linear() = T.linear().cast<float>();
    out.translation() = T.translation().cast<float>() * scale;
    return out;
}

/// Whether a link is a door or drawer front (the parts that define the model's front).
bool IsFrontSemantic(const std::string& s) {
    return s.find("door") != std::string::npos || s == "drawer";
}

}  // namespace

float ArticulatedJoint::Closed() const {
    if (type == io::UrdfJointType::kContinuous || lower > upper) return 0.0f;
    return std::clamp(0.0f, lower, upper);
}

float ArticulatedJoint::Opened(float fraction) const {
    if (type == io::UrdfJointType::kContinuous) {
        return fraction * 2.0f * std::numbers::pi_v<float>;
    }
    const float c = Closed();
    const float far = std::abs(upper - c) >= std::abs(lower - c) ? upper : lower;
    return c + fraction * (far - c);
}

std::vector<float> ArticulatedModel::ClosedState() const {
    std::vector<float> q;
    q.reserve(joints.size());
    for (const auto& j : joints) q.push_back(j.Closed());
    return q;
}

int ArticulatedModel::FindLink(const std::string& link_name) const {
    for (std::size_t i = 0; i < links.size(); ++i) {
        if (links[i].name == link_name) return static_cast<int>(i);
    }
    return -1;
}

std::vector<Eigen::Isometry3f> ArticulatedModel::LinkPoses(const std::vector<float>& q) const {
    if (q.size() != joints.size()) {
        throw InvalidArgument(
            fmt::format("model {}: {} joint values for {} joints", id, q.size(), joints.size()));
    }
    std::vector<Eigen::Isometry3f> poses(links.size(), Eigen::Isometry3f::Identity());
    std::vector<bool> done(links.size(), false);
    poses[static_cast<std::size_t>(root)] = T_model_root;
    done[static_cast<std::size_t>(root)] = true;
    // Links are few: resolve parents first by repeated passes (the URDF is a tree).
    for (std::size_t pass = 0; pass < links.size(); ++pass) {
        bool changed = false;
        for (std::size_t j = 0; j < joints.size(); ++j) {
            const ArticulatedJoint& jt = joints[j];
            const auto p = static_cast<std::size_t>(jt.parent);
            const auto c = static_cast<std::size_t>(jt.child);
            if (!done[p] || done[c]) continue;
            Eigen::Isometry3f motion = Eigen::Isometry3f::Identity();
            if (jt.type == io::UrdfJointType::kRevolute ||
                jt.type == io::UrdfJointType::kContinuous) {
                motion.linear() = Eigen::AngleAxisf(q[j], jt.axis).toRotationMatrix();
            } else if (jt.type == io::UrdfJointType::kPrismatic) {
                motion.translation() = q[j] * jt.axis;
            }
            poses[c] = poses[p] * jt.T_parent_joint * motion;
            done[c] = true;
            changed = true;
        }
        if (!changed) break;
    }
    return poses;
}

ArticulatedModel LoadArticulatedModel(const std::filesystem::path& folder,
                                      const ArticulatedLoadParams& params) {
    if (!(params.scale > 0.0f) || !std::isfinite(params.scale)) {
        throw InvalidArgument(
            fmt::format("articulated model scale must be > 0, got {}", params.scale));
    }
    if (params.texture_size == 0) throw InvalidArgument("texture_size must be > 0");
    const io::UrdfModel urdf = io::ReadUrdf(folder / "mobility.urdf");
    const auto semantics = ReadSemantics(folder / "semantics.txt");
    ArticulatedModel model;
    model.id = (folder.parent_path().filename() / folder.filename()).generic_string();
    model.scale = params.scale;
    TextureCache cache(params.texture_size);
    const Eigen::Affine3f S(Eigen::Scaling(params.scale));
    std::size_t missing = 0;
    for (const io::UrdfLink& l : urdf.links) {
        ArticulatedLink link;
        link.name = l.name;
        const auto sem = semantics.find(l.name);
        link.joint_kind = sem == semantics.end() ? "unknown" : sem->second.first;
        link.semantic = sem == semantics.end() ? "unknown" : sem->second.second;
        if (!l.visuals.empty()) {
            PartMesh mesh;
            mesh.name = model.id + "/" + l.name;
            std::vector<float> reflectance;
            for (const io::UrdfVisual& v : l.visuals) {
                if (v.geometry.kind != io::UrdfGeometry::Kind::kMesh) continue;
                std::error_code ec;
                if (!std::filesystem::is_regular_file(folder / v.geometry.filename, ec)) {
                    if (params.strict) {
                        throw IoError(fmt::format("{}: no such part mesh",
                                                  (folder / v.geometry.filename).string()));
                    }
                    ++missing;
                    continue;
                }
                const Eigen::Affine3f T =
                    S * Eigen::Affine3f(v.origin.cast<float>().matrix()) *
                    Eigen::Affine3f(Eigen::Scaling(v.geometry.scale.cast<float>()));
                AppendVisual(folder / v.geometry.filename, T, PartName(v.name), cache, mesh,
                             reflectance);
            }
            if (!mesh.mesh.triangles.empty()) {
                mesh.vertex_reflectance = std::move(reflectance);
                mesh.Validate();
                link.mesh = std::make_shared<const PartMesh>(std::move(mesh));
            }
        }
        model.links.push_back(std::move(link));
    }
    for (const io::UrdfJoint& j : urdf.joints) {
        ArticulatedJoint joint;
        joint.name = j.name;
        joint.type = j.type;
        joint.parent = model.FindLink(j.parent);
        joint.child = model.FindLink(j.child);
        joint.T_parent_joint = ToFloat(j.origin, params.scale);
        const double n = j.axis.norm();
        joint.axis = n > 0.0 ? Eigen::Vector3f((j.axis / n).cast<float>())
                             : Eigen::Vector3f(Eigen::Vector3f::UnitX());
        const float limit_scale = j.type == io::UrdfJointType::kPrismatic ? params.scale : 1.0f;
        if (j.has_limits) {
            joint.lower = static_cast<float>(j.lower) * limit_scale;
            joint.upper = static_cast<float>(j.upper) * limit_scale;
        }
        model.links[static_cast<std::size_t>(joint.child)].parent_joint =
            static_cast<int>(model.joints.size());
        model.joints.push_back(joint);
    }
    model.root = std::max(0, model.FindLink(urdf.root));
    if (missing > 0) {
        LogInfo("{}: {} visuals name missing part meshes; the model is loaded without them",
                folder.string(), missing);
    }

    // The front: the mean horizontal way the door and drawer centroids move when opened a little.
    const std::vector<float> closed = model.ClosedState();
    const auto poses0 = model.LinkPoses(closed);
    Eigen::Vector3f front_sum = Eigen::Vector3f::Zero();
    for (std::size_t j = 0; j < model.joints.size(); ++j) {
        const auto& jt = model.joints[j];
        const auto& child = model.links[static_cast<std::size_t>(jt.child)];
        if (!jt.Movable() || jt.type == io::UrdfJointType::kContinuous || !child.mesh ||
            !IsFrontSemantic(child.semantic)) {
            continue;
        }
        std::vector<float> q = closed;
        q[j] = jt.Opened(0.15f);
        const auto poses1 = model.LinkPoses(q);
        const Eigen::Vector3f c = child.mesh->Bounds().center();
        Eigen::Vector3f d = poses1[static_cast<std::size_t>(jt.child)] * c -
                            poses0[static_cast<std::size_t>(jt.child)] * c;
        d.z() = 0.0f;
        if (d.norm() > 1e-6f) front_sum += d.normalized();
    }
    float yaw = static_cast<float>(std::numbers::pi);  // PartNet-Mobility's usual front is -x
    if (front_sum.norm() > 1e-3f) {
        const float a = std::atan2(front_sum.y(), front_sum.x());
        const float snapped =
            std::round(a / (std::numbers::pi_v<float> / 2)) * (std::numbers::pi_v<float> / 2);
        yaw = -snapped;
    }
    Eigen::Isometry3f R = Eigen::Isometry3f::Identity();
    R.linear() = Eigen::AngleAxisf(yaw, Eigen::Vector3f::UnitZ()).toRotationMatrix();
    model.T_model_root = R;
    Eigen::AlignedBox3f box;
    const auto poses = model.LinkPoses(closed);
    for (std::size_t l = 0; l < model.links.size(); ++l) {
        if (!model.links[l].mesh) continue;
        for (const auto& v : model.links[l].mesh->mesh.vertices) box.extend(poses[l] * v);
    }
    if (box.isEmpty()) {
        throw DataError(fmt::format("{}: model has no visual geometry", folder.string()));
    }
    Eigen::Isometry3f shift = Eigen::Isometry3f::Identity();
    shift.translation() = Eigen::Vector3f(-box.center().x(), -box.center().y(), -box.min().z());
    model.T_model_root = shift * R;
    model.bounds =
        Eigen::AlignedBox3f(box.min() + shift.translation(), box.max() + shift.translation());
    return model;
}

}  // namespace multicue::sim
