// Mesh files through Assimp: every mesh of the file, placed by its node transforms, in one list.
// Assimp reads nothing itself: GateIOSystem hands it each file from memory, read through the
// scene's FileGate.
#include <assimp/IOStream.hpp>
#include <assimp/IOSystem.hpp>
#include <assimp/Importer.hpp>
#include <assimp/ProgressHandler.hpp>
#include <assimp/postprocess.h>
#include <assimp/scene.h>
#include <fmt/format.h>

#include <algorithm>
#include <cstring>
#include <filesystem>
#include <map>
#include <memory>
#include <mutex>
#include <unordered_set>

#include "io/file_gate.h"
#include "scene/assimp_scene.h"
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
    const std::vector<int>* parts = nullptr;  // only these meshes; null or empty = all

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
            if (parts && !parts->empty() && std::find(parts->begin(), parts->end(), int(mi)) == parts->end()) continue;
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

// A file's bytes as Assimp reads them. The bytes belong to the GateIOSystem, and so does every
// stream: Assimp deletes most streams itself (often directly, not through Close), but on some
// errors it forgets one (its OBJ importer with a broken .mtl, its glTF importer with a short
// buffer). A stream unregisters itself when deleted; the IOSystem deletes those left over when
// the importer goes, so a forgotten stream costs neither a descriptor nor memory.
class MemoryStream;
using StreamSet = std::unordered_set<MemoryStream*>;

class MemoryStream : public Assimp::IOStream {
  public:
    MemoryStream(const std::string* bytes, const std::function<bool()>* cancelled, StreamSet* live)
        : bytes_(bytes), cancelled_(cancelled), live_(live) {
        live_->insert(this);
    }
    ~MemoryStream() override { live_->erase(this); }
    size_t Read(void* buffer, size_t size, size_t count) override {
        // Parsers read in chunks as they go (OBJ: 1 MiB at a time): a cancel lands between two.
        if (*cancelled_ && (*cancelled_)()) throw BuildCancelled();
        if (size == 0) return 0;
        const size_t n = std::min(count, (bytes_->size() - pos_) / size);
        std::memcpy(buffer, bytes_->data() + pos_, n * size);
        pos_ += n * size;
        return n;
    }
    size_t Write(const void*, size_t, size_t) override { return 0; }
    aiReturn Seek(size_t offset, aiOrigin origin) override {
        size_t base = origin == aiOrigin_SET ? 0 : origin == aiOrigin_CUR ? pos_ : bytes_->size();
        if (offset > bytes_->size() - std::min(base, bytes_->size()) && origin != aiOrigin_END) return aiReturn_FAILURE;
        size_t to = origin == aiOrigin_END ? bytes_->size() - std::min(offset, bytes_->size()) : base + offset;
        if (to > bytes_->size()) return aiReturn_FAILURE;
        pos_ = to;
        return aiReturn_SUCCESS;
    }
    size_t Tell() const override { return pos_; }
    size_t FileSize() const override { return bytes_->size(); }
    void Flush() override {}

  private:
    const std::string* bytes_;
    const std::function<bool()>* cancelled_;
    StreamSet* live_;
    size_t pos_ = 0;
};

// Every open Assimp makes goes through the gate; relative names resolve against the mesh
// file's folder. Owned by the Assimp::Importer (it deletes its IO handler).
class GateIOSystem : public Assimp::IOSystem {
  public:
    GateIOSystem(const FileGate& gate, std::string dir, const MeshFileOptions& opt) : gate_(gate), dir_(std::move(dir)), opt_(opt) {}

    // A probe reads nothing, so its refusal refuses nothing (importers probe for optional files).
    bool Exists(const char* file) const override {
        try {
            gate_.check(resolve(file));
            return true;
        } catch (const FileRefused&) {
            return false;
        }
    }
    char getOsSeparator() const override { return '/'; }
    Assimp::IOStream* Open(const char* file, const char* mode) override {
        if (std::strpbrk(mode, "wa+")) return nullptr;  // Assimp only reads here
        const std::string path = resolve(file);
        auto it = files_.find(path);
        if (it == files_.end()) {
            try {
                it = files_.emplace(path, gate_.read(path)).first;
            } catch (const FileRefused& e) {
                note_refusal(e.what());
                return nullptr;
            }
            if (opt_.on_read) opt_.on_read(path);
        }
        return new MemoryStream(&it->second, &opt_.cancelled, &live_);
    }
    void Close(Assimp::IOStream* stream) override { delete stream; }
    ~GateIOSystem() override {
        while (!live_.empty()) delete *live_.begin();  // streams Assimp forgot; each unregisters itself
    }

    // The first refusal, if any: a confined gate's refusal of any file refuses the mesh.
    const std::string& refusal() const { return refusal_; }

  private:
    std::string resolve(const char* file) const {
        std::filesystem::path p(file);
        return (p.is_relative() ? std::filesystem::path(dir_) / p : p).lexically_normal().string();
    }
    void note_refusal(const std::string& what) {
        if (refusal_.empty()) refusal_ = what;
    }

    const FileGate& gate_;
    std::string dir_;
    const MeshFileOptions& opt_;
    std::map<std::string, std::string> files_;  // every file read, by absolute path
    StreamSet live_;                             // every stream not yet deleted
    std::string refusal_;
};

// Assimp reports progress while it parses (OBJ: every 100 KiB) and between post-processing
// steps, but most importers ignore Update's answer: a cancel throws instead, which unwinds the
// importer like one of its own DeadlyImportErrors (ReadFile catches it, or it reaches our caller).
class CancelPoll : public Assimp::ProgressHandler {
  public:
    explicit CancelPoll(std::function<bool()> cancelled) : cancelled_(std::move(cancelled)) {}
    bool Update(float) override {
        if (cancelled_ && cancelled_()) throw BuildCancelled();
        return true;
    }

  private:
    std::function<bool()> cancelled_;
};

// Debian's Assimp 5.2 writes process-global state while importing (TSan saw two omegad
// workers' Scene::build race on a global inside libassimp during ReadFile), so imports are
// serialised. Any thread may call load_mesh_file; it holds this lock only around the import.
std::mutex& assimp_mutex() {
    static std::mutex m;
    return m;
}

TriangleMesh merge_meshes(const aiScene* scene, const std::string& at, const std::string& name,
                          const MeshFileOptions& opt);

}  // namespace

void read_assimp_scene(const FileGate& gate, const std::string& path, const SourceLoc& loc, const MeshFileOptions& opt,
                       unsigned post_process, const std::function<void(const aiScene&)>& use) {
    std::string at = loc.key.empty() ? fmt::format("{}:{}: ", loc.file, loc.line)
                                     : fmt::format("{}:{}: {}: ", loc.file, loc.line, loc.key);
    const std::string name = opt.written.empty() ? gate.shown(path) : opt.written;
    const std::string abs = std::filesystem::absolute(path).lexically_normal().string();
    // The mesh file itself is checked before Assimp runs, so its refusal names it as written.
    try {
        gate.check(abs, opt.written);
    } catch (const FileRefused& e) {
        throw SceneError(at + e.what());
    }
    // Assimp's messages may hold the path it was given: a client sees the scene's name instead.
    auto clean = [&](std::string msg) {
        const std::string dir = std::filesystem::path(abs).parent_path().string() + "/";
        for (const std::string* from : {&abs, &dir})
            for (std::size_t pos; (pos = msg.find(*from)) != std::string::npos;)
                msg.replace(pos, from->size(), from == &abs ? name : std::string());
        return msg;
    };
    // Held across Assimp's parse and its reads of regular files admitted by the gate (read
    // whole, non-blocking): nothing under it can wait on another process.
    std::lock_guard<std::mutex> lock(assimp_mutex());
    Assimp::Importer importer;
    auto* io = new GateIOSystem(gate, std::filesystem::path(abs).parent_path().string(), opt);
    importer.SetIOHandler(io);  // the importer owns it
    importer.SetProgressHandler(new CancelPoll(opt.cancelled));
    const aiScene* scene = importer.ReadFile(abs, post_process);
    if (opt.cancelled && opt.cancelled()) throw BuildCancelled();
    if (gate.is_confined() && !io->refusal().empty())
        throw SceneError(fmt::format("{}mesh '{}': {}", at, name, io->refusal()));
    if (!scene || (scene->mFlags & AI_SCENE_FLAGS_INCOMPLETE) || !scene->mRootNode)
        throw SceneError(fmt::format("{}cannot load mesh '{}': {}", at, name, clean(importer.GetErrorString())));
    use(*scene);
}

TriangleMesh load_mesh_file(const FileGate& gate, const std::string& path, const SourceLoc& loc,
                            const MeshFileOptions& opt) {
    std::string at = loc.key.empty() ? fmt::format("{}:{}: ", loc.file, loc.line)
                                     : fmt::format("{}:{}: {}: ", loc.file, loc.line, loc.key);
    const std::string name = opt.written.empty() ? gate.shown(path) : opt.written;
    TriangleMesh mesh;
    // No normal generation: a file without normals is shaded flat, as its author made it.
    read_assimp_scene(gate, path, loc, opt, aiProcess_Triangulate | aiProcess_JoinIdenticalVertices,
                      [&](const aiScene& s) { mesh = merge_meshes(&s, at, name, opt); });
    return mesh;
}

namespace {
TriangleMesh merge_meshes(const aiScene* scene, const std::string& at, const std::string& name,
                          const MeshFileOptions& opt) {
    Merger merger{scene, {}, true, {}};
    merger.flip_v = opt.flip_tex_coords;
    merger.parts = &opt.parts;
    for (int p : opt.parts)
        if (p < 0 || unsigned(p) >= scene->mNumMeshes)
            throw SceneError(fmt::format("{}mesh '{}': meshes: the file has no mesh {} (it has {})", at, name, p,
                                         scene->mNumMeshes));
    merger.visit(scene->mRootNode, aiMatrix4x4(), 0);
    if (!merger.error.empty()) throw SceneError(fmt::format("{}mesh '{}': {}", at, name, merger.error));
    if (merger.out.indices.empty()) throw SceneError(fmt::format("{}mesh '{}' has no triangles", at, name));
    // Shading normals only make sense if every vertex has one.
    if (!merger.all_have_normals) merger.out.normals.clear();
    if (!merger.any_uvs) merger.out.uvs.clear();
    return std::move(merger.out);
}
}  // namespace

}  // namespace omega
