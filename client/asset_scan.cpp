#include "asset_scan.h"

#include <fmt/format.h>
#include <openssl/evp.h>
#include <yaml-cpp/yaml.h>

#include <filesystem>
#include <fstream>
#include <map>
#include <memory>
#include <sstream>

#include "client_error.h"
#include "scene/scene_error.h"
#include "io/file_gate.h"
#include "scene/gltf_importer.h"
#include "scene/mitsuba_importer.h"
#include "scene/scene_parser.h"
#include "scene/scene_writer.h"
#include "scene/triangle_mesh.h"

namespace omega::client {

namespace fs = std::filesystem;

namespace {

struct MdCtx {
    EVP_MD_CTX* c = EVP_MD_CTX_new();
    ~MdCtx() { EVP_MD_CTX_free(c); }
};

std::string hex(const unsigned char* d, unsigned n) {
    static const char* k = "0123456789abcdef";
    std::string s;
    for (unsigned i = 0; i < n; ++i) {
        s += k[d[i] >> 4];
        s += k[d[i] & 15];
    }
    return s;
}

// A name the protocol accepts as is: relative, '/'-separated, no empty, '.' or '..' component.
bool clean_relative(const std::string& s) {
    if (s.empty() || s.front() == '/' || s.find('\\') != std::string::npos || s.find('\0') != std::string::npos)
        return false;
    std::stringstream ss(s);
    std::string part;
    size_t count = 0;
    while (std::getline(ss, part, '/')) {
        if (part.empty() || part == "." || part == "..") return false;
        ++count;
    }
    return count > 0 && s.back() != '/';
}

std::string read_file(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    if (!in) throw ClientError(kExitBadInput, fmt::format("{}: cannot open the scene file", path));
    std::stringstream ss;
    ss << in.rdbuf();
    return ss.str();
}

}  // namespace

std::string sha256_bytes(const std::string& bytes) {
    unsigned char md[EVP_MAX_MD_SIZE];
    unsigned n = 0;
    MdCtx ctx;
    if (!ctx.c || !EVP_DigestInit_ex(ctx.c, EVP_sha256(), nullptr) ||
        !EVP_DigestUpdate(ctx.c, bytes.data(), bytes.size()) || !EVP_DigestFinal_ex(ctx.c, md, &n))
        throw ClientError(kExitInternal, "SHA-256 failed");
    return hex(md, n);
}

std::string sha256_file(const std::string& path, uint64_t* size) {
    std::ifstream in(path, std::ios::binary);
    if (!in) throw ClientError(kExitBadInput, fmt::format("{}: cannot read", path));
    MdCtx ctx;
    if (!ctx.c || !EVP_DigestInit_ex(ctx.c, EVP_sha256(), nullptr)) throw ClientError(kExitInternal, "SHA-256 failed");
    std::vector<char> buf(1 << 20);
    uint64_t total = 0;
    while (in) {
        in.read(buf.data(), std::streamsize(buf.size()));
        const auto got = in.gcount();
        if (got > 0) {
            EVP_DigestUpdate(ctx.c, buf.data(), size_t(got));
            total += uint64_t(got);
        }
    }
    if (in.bad()) throw ClientError(kExitBadInput, fmt::format("{}: read error", path));
    unsigned char md[EVP_MAX_MD_SIZE];
    unsigned n = 0;
    EVP_DigestFinal_ex(ctx.c, md, &n);
    if (size) *size = total;
    return hex(md, n);
}

std::vector<protocol::AssetRef> ScannedScene::refs() const {
    std::vector<protocol::AssetRef> out;
    for (const auto& a : assets) out.push_back({a.name, a.sha256, a.size});
    return out;
}

ScannedScene scan_scene(const std::string& scene_path) {
    ScannedScene s;
    s.path = scene_path;
    s.name = fs::path(scene_path).stem().string();
    const fs::path dir = fs::path(scene_path).parent_path().empty() ? fs::path(".") : fs::path(scene_path).parent_path();
    SceneDesc desc;
    // Images embedded in the scene file, by the relative name the YAML gives them.
    std::map<std::string, std::shared_ptr<const EmbeddedImage>> embedded;
    try {
        if (is_mitsuba_path(scene_path) || is_gltf_path(scene_path)) {
            // Imported here, as `omega import` does: what travels is the v1 YAML it writes (equal
            // to the import when parsed again, scene_writer.h), with every file it names relative
            // to the scene's folder, so the walk below finds and sends them.
            SceneDesc imported = load_scene_file(scene_path);
            const std::string yaml_path = (dir / (s.name + ".yaml")).string();
            const std::string images = embedded_image_dir(yaml_path);
            for (const EmbeddedFile& f : embedded_files(imported, images)) embedded[f.rel] = f.image;
            s.yaml = write_scene_yaml(imported, dir.string(), images);
            // Parsed again as omegad will parse it, unless it names embedded images: their files
            // exist only as bytes here (and the parser checks that each file it names exists).
            std::vector<std::string> warnings = imported.warnings;
            desc = embedded.empty() ? parse_scene_string(s.yaml, yaml_path) : std::move(imported);
            desc.warnings = std::move(warnings);
        } else {
            s.yaml = read_file(scene_path);
            desc = parse_scene_string(s.yaml, scene_path);
        }
    } catch (const SceneError& e) {
        throw ClientError(kExitBadInput, e.what());
    }
    s.warnings = desc.warnings;

    // The parser validated every shape; walk the same YAML for the `file:` strings as written.
    YAML::Node root = YAML::Load(s.yaml);
    YAML::Node shapes = root["shapes"];
    bool rewritten = false;
    std::map<std::string, size_t> by_name;
    // One `file:` of a mesh shape or a bitmap texture: hashed, and renamed when not a clean relative path.
    auto add = [&](ScannedAsset a) {
        if (auto it = by_name.find(a.name); it != by_name.end()) return;  // same file twice
        by_name[a.name] = s.assets.size();
        s.assets.push_back(std::move(a));
    };
    // The files a mesh names inside itself (an OBJ's mtllib, a glTF's buffers) travel beside it,
    // under the same relative names: the daemon's loader reads only submitted files.
    auto take_inner = [&](const ScannedAsset& mesh, const std::string& written) {
        const fs::path mesh_dir = fs::path(mesh.path).parent_path();
        const fs::path name_dir = fs::path(mesh.name).parent_path();
        std::vector<std::string> inner;
        MeshFileOptions opt;
        opt.written = written;
        opt.on_read = [&](const std::string& p) {
            if (p != fs::path(mesh.path).lexically_normal().string()) inner.push_back(p);
        };
        try {
            (void)load_mesh_file(*FileGate::unconfined(), mesh.path, {scene_path, 0, ""}, opt);
        } catch (const SceneError&) {
            // omegad reports a bad mesh with the scene's line; nothing more to send for it
        }
        for (const std::string& p : inner) {
            const std::string rel = fs::path(p).lexically_relative(mesh_dir).generic_string();
            if (!clean_relative(rel)) {
                s.warnings.push_back(fmt::format("{}: mesh '{}' names '{}' outside its own folder; it is not sent, and "
                                                 "omegad will refuse the mesh",
                                                 scene_path, written, p));
                continue;
            }
            ScannedAsset a;
            a.path = p;
            a.sha256 = sha256_file(p, &a.size);
            a.name = (name_dir / rel).generic_string();
            add(std::move(a));
        }
    };
    auto take = [&](YAML::Node holder) {
        if (!holder.IsMap() || !holder["file"] || !holder["file"].IsScalar()) return;
        const bool mesh = holder["type"] && holder["type"].IsScalar() && holder["type"].as<std::string>() == "mesh";
        const std::string written = holder["file"].as<std::string>();
        if (auto e = embedded.find(written); e != embedded.end()) {
            ScannedAsset a;
            a.name = written;  // clean and relative: "<stem>_textures/<name>"
            a.path = scene_path + "#" + written;
            a.data = std::shared_ptr<const std::string>(e->second, &e->second->bytes);
            a.sha256 = sha256_bytes(*a.data);
            a.size = a.data->size();
            add(std::move(a));
            return;
        }
        fs::path p(written);
        if (p.is_relative()) p = dir / p;
        ScannedAsset a;
        a.path = p.lexically_normal().string();
        a.sha256 = sha256_file(a.path, &a.size);
        if (clean_relative(written)) {
            a.name = written;
        } else {
            a.name = "assets/" + a.sha256.substr(0, 16) + "/" + fs::path(written).filename().string();
            holder["file"] = a.name;
            rewritten = true;
        }
        if (mesh) take_inner(a, written);
        add(std::move(a));
    };
    // Textures of a named or an inline material: every parameter that takes a bitmap (a
    // checkerboard names no file, and take() passes over it).
    auto take_material = [&](YAML::Node m) {
        for (const char* key : {"reflectance", "diffuse_reflectance", "specular_reflectance", "opacity", "bump"})
            if (m.IsMap() && m[key] && m[key].IsMap()) take(m[key]);
    };
    if (YAML::Node mats = root["materials"]; mats && mats.IsMap())
        for (auto it = mats.begin(); it != mats.end(); ++it) take_material(it->second);
    if (shapes && shapes.IsSequence()) {
        for (size_t i = 0; i < shapes.size(); ++i) {
            take(shapes[i]);
            if (shapes[i].IsMap() && shapes[i]["material"]) take_material(shapes[i]["material"]);
        }
    }
    // An envmap light's image.
    if (YAML::Node lights = root["lights"]; lights && lights.IsSequence())
        for (size_t i = 0; i < lights.size(); ++i)
            if (lights[i].IsMap() && lights[i]["type"] && lights[i]["type"].IsScalar() &&
                lights[i]["type"].as<std::string>() == "envmap")
                take(lights[i]);
    if (rewritten) {
        YAML::Emitter em;
        em << root;
        s.yaml = std::string(em.c_str()) + "\n";
    }
    return s;
}

}  // namespace omega::client
