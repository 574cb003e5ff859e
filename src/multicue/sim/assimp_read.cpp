#include "multicue/sim/assimp_read.hpp"

#include <assimp/BaseImporter.h>
#include <assimp/postprocess.h>
#include <assimp/scene.h>
#include <fmt/format.h>
#include <assimp/Importer.hpp>

#include "multicue/core/exceptions.hpp"

namespace multicue::sim::assimp_read {

using Assimp::BaseImporter;

const aiScene* ReadScene(Assimp::Importer& importer, const std::filesystem::path& path,
                         unsigned post_steps) {
    // Assimp never reads PLY here (its importer crashed, asserted and looped on damaged files;
    // LoadMesh reads PLY with multicue's reader): its PLY loader is taken out of this importer,
    // so that a PLY file behind another name is refused instead.
    if (BaseImporter* ply = importer.GetImporter("ply"); ply != nullptr) {
        if (importer.UnregisterLoader(ply) == aiReturn_SUCCESS) delete ply;
    }
    const aiScene* read = importer.ReadFile(path.string(), aiProcess_ValidateDataStructure);
    if (read == nullptr || read->mRootNode == nullptr) {
        throw FormatError(
            fmt::format("{}: cannot read mesh: {}", path.string(), importer.GetErrorString()));
    }
    // The importer owns the scene, which it allocated as a mutable object and hands out as const;
    // it is adjusted here before any post-processing step reads it.
    auto* scene = const_cast<aiScene*>(read);  // NOLINT(cppcoreguidelines-pro-type-const-cast)
    for (unsigned m = 0; m < scene->mNumMeshes; ++m) {
        aiMesh* mesh = scene->mMeshes[m];
        if (mesh == nullptr) {
            throw FormatError(fmt::format("{}: mesh {} is missing", path.string(), m));
        }
        unsigned types = 0;
        for (unsigned f = 0; f < mesh->mNumFaces; ++f) {
            const unsigned n = mesh->mFaces[f].mNumIndices;
            if (n == 0 || mesh->mFaces[f].mIndices == nullptr) {
                throw FormatError(fmt::format("{}: face {} of mesh {} has no vertex indices",
                                              path.string(), f, m));
            }
            types |= n == 1   ? aiPrimitiveType_POINT
                     : n == 2 ? aiPrimitiveType_LINE
                     : n == 3 ? aiPrimitiveType_TRIANGLE
                              : aiPrimitiveType_POLYGON;
        }
        mesh->mPrimitiveTypes = types;
    }
    const aiScene* out = importer.ApplyPostProcessing(post_steps);
    if (out == nullptr || out->mRootNode == nullptr) {
        throw FormatError(
            fmt::format("{}: cannot read mesh: {}", path.string(), importer.GetErrorString()));
    }
    return out;
}

}  // namespace multicue::sim::assimp_read
