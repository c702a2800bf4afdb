// Mesh files through Assimp: every mesh of the file, placed by its node transforms, in one list.
#include <assimp/Importer.hpp>
#include <assimp/postprocess.h>
#include <assimp/scene.h>
#include <fmt/format.h>

#include <mutex>

#include "scene/scene_error.h"
#include "scene/triangle_mesh.h"

namespace omega {

namespace {

struct Merger {
    const aiScene* scene;
    TriangleMesh out;
    bool all_have_normals = true;
    std::string error;
    bool any_uvs = false;
    bool flip_v = true;

    void visit(const aiNode* node, const aiMatrix4x4& parent, int depth) {
        if (depth > 256) {  // a cyclic or absurd node graph must not overflow the stack
            error = "node hierarchy too deep";
            return;
        }
        aiMatrix4x4 m = parent * node->mTransformation;
        aiMatrix3x3 nm = aiMatrix3x3(m);
        nm.Inverse().Transpose();  // normals by the inverse transpose
        for (unsigned i = 0; i < node->mNumMeshes && error.empty(); ++i) {
            unsigned mi = node->mMeshes[i];
            if (mi >= scene->mNumMeshes) {
                error = "node references a missing mesh";
                return;
            }
            add(scene->mMeshes[mi], m, nm);
        }
        for (unsigned c = 0; c < node->mNumChildren && error.empty(); ++c) visit(node->mChildren[c], m, depth + 1);
    }

    void add(const aiMesh* mesh, const aiMatrix4x4& m, const aiMatrix3x3& nm) {
        if (!(mesh->mPrimitiveTypes & aiPrimitiveType_TRIANGLE)) return;  // points and lines have no area
        uint64_t base = out.positions.size();
        if (base + mesh->mNumVertices > UINT32_MAX) {
            error = "too many vertices";
            return;
        }
        bool has_n = mesh->HasNormals();
        all_have_normals &= has_n;
        bool has_uv = mesh->HasTextureCoords(0);
        any_uvs |= has_uv;
        for (unsigned v = 0; v < mesh->mNumVertices; ++v) {
            aiVector3D p = m * mesh->mVertices[v];
            out.positions.push_back({p.x, p.y, p.z});
            if (has_n) {
                aiVector3D n = nm * mesh->mNormals[v];
                out.normals.push_back({n.x, n.y, n.z});
            } else {
                out.normals.push_back({0, 0, 0});
            }
            // A part without uvs gets (0, 0): only the parts that have them are textured meaningfully.
            Vec2 uv{};
            if (has_uv) uv = {mesh->mTextureCoords[0][v].x, mesh->mTextureCoords[0][v].y};
            if (has_uv && flip_v) uv.y = 1.f - uv.y;
            out.uvs.push_back(uv);
        }
        for (unsigned f = 0; f < mesh->mNumFaces; ++f) {
            const aiFace& face = mesh->mFaces[f];
            if (face.mNumIndices != 3) continue;
            for (int k = 0; k < 3; ++k) {
                if (face.mIndices[k] >= mesh->mNumVertices) {
                    error = "face index out of range";
                    return;
                }
                out.indices.push_back(uint32_t(base + face.mIndices[k]));
            }
        }
    }
};

// Debian's Assimp 5.2 writes process-global state while importing (TSan saw two omegad
// workers' Scene::build race on a global inside libassimp during ReadFile), so imports are
// serialised. Any thread may call load_mesh_file; it holds this lock only inside Assimp.
std::mutex& assimp_mutex() {
    static std::mutex m;
    return m;
}

}  // namespace

TriangleMesh load_mesh_file(const std::string& path, const SourceLoc& loc, bool flip_tex_coords) {
    std::string at = loc.key.empty() ? fmt::format("{}:{}: ", loc.file, loc.line)
                                     : fmt::format("{}:{}: {}: ", loc.file, loc.line, loc.key);
    std::lock_guard<std::mutex> lock(assimp_mutex());
    Assimp::Importer importer;
    // No normal generation: a file without normals is shaded flat, as its author made it.
    const aiScene* scene = importer.ReadFile(path, aiProcess_Triangulate | aiProcess_JoinIdenticalVertices);
    if (!scene || (scene->mFlags & AI_SCENE_FLAGS_INCOMPLETE) || !scene->mRootNode)
        throw SceneError(fmt::format("{}cannot load mesh '{}': {}", at, path, importer.GetErrorString()));
    Merger merger{scene, {}, true, {}};
    merger.flip_v = flip_tex_coords;
    merger.visit(scene->mRootNode, aiMatrix4x4(), 0);
    if (!merger.error.empty()) throw SceneError(fmt::format("{}mesh '{}': {}", at, path, merger.error));
    if (merger.out.indices.empty()) throw SceneError(fmt::format("{}mesh '{}' has no triangles", at, path));
    // Shading normals only make sense if every vertex has one.
    if (!merger.all_have_normals) merger.out.normals.clear();
    if (!merger.any_uvs) merger.out.uvs.clear();
    return std::move(merger.out);
}

}  // namespace omega
