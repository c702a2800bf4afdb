// glTF 2.0 -> SceneDesc (scene/gltf_importer.h; the mapping is documented in docs/scene-format.md).
#include "scene/gltf_importer.h"

#include <assimp/GltfMaterial.h>
#include <assimp/material.h>
#include <assimp/scene.h>
#include <fmt/format.h>
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <functional>
#include <map>
#include <optional>
#include <set>
#include <vector>

#include "io/file_gate.h"
#include "scene/assimp_scene.h"
#include "scene/param_bag.h"
#include "scene/scene_error.h"
#include "scene/scene_files.h"
#include "scene/scene_parser.h"
#include "texture/image.h"

namespace omega {

namespace fs = std::filesystem;

namespace {

constexpr double kPi = 3.14159265358979323846;

// Extensions whose content the importer reads (or, for the lights, Assimp reads for it).
const std::set<std::string> kKnownExtensions = {"KHR_lights_punctual", "KHR_materials_emissive_strength"};

Vec3d xform_point(const Mat4& m, const Vec3d& p) {
    return {m(0, 0) * p.x + m(0, 1) * p.y + m(0, 2) * p.z + m(0, 3), m(1, 0) * p.x + m(1, 1) * p.y + m(1, 2) * p.z + m(1, 3),
            m(2, 0) * p.x + m(2, 1) * p.y + m(2, 2) * p.z + m(2, 3)};
}
Vec3d xform_dir(const Mat4& m, const Vec3d& d) {
    return {m(0, 0) * d.x + m(0, 1) * d.y + m(0, 2) * d.z, m(1, 0) * d.x + m(1, 1) * d.y + m(1, 2) * d.z,
            m(2, 0) * d.x + m(2, 1) * d.y + m(2, 2) * d.z};
}
Vec3d unit(const Vec3d& v) {
    double l = std::sqrt(v.x * v.x + v.y * v.y + v.z * v.z);
    return l > 0 ? Vec3d{v.x / l, v.y / l, v.z / l} : v;
}
Vec3d cross3(const Vec3d& a, const Vec3d& b) {
    return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}

// glTF cameras and lights look along their node's local -z with +y up; Omega's sensor and spot
// look along +z with +x = up x direction (Mitsuba's frame). This is that frame, orthonormal and
// without the node's scale, placed at the node's origin.
Mat4 omega_frame(const Mat4& node) {
    Vec3d o = xform_point(node, {0, 0, 0});
    Vec3d z = unit(xform_dir(node, {0, 0, -1}));
    Vec3d x = unit(cross3(xform_dir(node, {0, 1, 0}), z));
    Vec3d y = cross3(z, x);
    Mat4 m;
    const Vec3d cols[4] = {x, y, z, o};
    for (int c = 0; c < 4; ++c) {
        m(0, c) = cols[c].x;
        m(1, c) = cols[c].y;
        m(2, c) = cols[c].z;
    }
    return m;
}

Mat4 to_mat4(const aiMatrix4x4& a) {
    Mat4 m;
    const float* p = &a.a1;  // row-major, a4 = translation x
    for (size_t i = 0; i < 16; ++i) m.m[i] = double(p[i]);
    return m;
}

std::string yaml_number(double v) { return fmt::format("{}", v); }  // shortest round-trip form
YAML::Node rgb_node(const Rgb& c) {
    YAML::Node n(YAML::NodeType::Sequence);
    for (int i = 0; i < 3; ++i) n.push_back(yaml_number(double(c[i])));
    return n;
}
YAML::Node vec_node(const Vec3d& v) {
    YAML::Node n(YAML::NodeType::Sequence);
    for (double x : {v.x, v.y, v.z}) n.push_back(yaml_number(x));
    return n;
}
YAML::Node matrix_node(const Mat4& m) {
    YAML::Node l(YAML::NodeType::Sequence);
    for (double v : m.m) l.push_back(yaml_number(std::abs(v) < 1e-15 ? 0.0 : v));
    YAML::Node n(YAML::NodeType::Map);
    n["matrix"] = l;
    return n;
}

// A uri's percent-escapes decoded (glTF uris are RFC 3986 references).
std::string uri_decode(const std::string& s) {
    std::string out;
    for (size_t i = 0; i < s.size(); ++i) {
        if (s[i] == '%' && i + 2 < s.size() && std::isxdigit(static_cast<unsigned char>(s[i + 1])) &&
            std::isxdigit(static_cast<unsigned char>(s[i + 2]))) {
            out += char(std::stoi(s.substr(i + 1, 2), nullptr, 16));
            i += 2;
        } else {
            out += s[i];
        }
    }
    return out;
}

class GltfImporter {
  public:
    GltfImporter(const std::string& path, const GltfOptions& opt)
        : path_(path), opt_(opt), fname_(std::make_shared<const std::string>(path)) {
        dir_ = fs::path(path).parent_path();
        if (dir_.empty()) dir_ = ".";
        shown_ = fs::path(path).filename().string();
    }

    SceneDesc run();

  private:
    const FileGate& gate() const { return opt_.files ? *opt_.files : *FileGate::unconfined(); }
    [[noreturn]] void fail(const std::string& key, const std::string& what) const {
        throw SceneError(fmt::format("{}:1: {}: {}", path_, key, what));
    }
    void warn(const std::string& object, const std::string& what) {
        desc_.warnings.push_back(fmt::format("{}: {}: {}", path_, object, what));
    }
    // An approximation: one warning per kind, naming every object it applies to (in note order).
    void note(const std::string& kind, const std::string& object) {
        auto& objs = notes_[kind];
        if (std::find(objs.begin(), objs.end(), object) == objs.end()) objs.push_back(object);
        if (objs.size() == 1) note_order_.push_back(kind);
    }
    void flush_notes() {
        for (const std::string& kind : note_order_) {
            std::string objs;
            for (const std::string& o : notes_[kind]) objs += (objs.empty() ? "" : ", ") + o;
            warn(objs, kind);
        }
    }

    void read_json();
    void check_uris(const char* array);
    void index_nodes(const aiNode* n, const Mat4& parent, int depth);
    void read_camera(const aiScene& s);
    void read_lights(const aiScene& s);
    void read_materials_and_shapes(const aiScene& s);
    std::string read_material(const aiMaterial& m, unsigned index, std::optional<EmitterDesc>& emitter);
    // An image a material names: a file beside the glTF, or one embedded in it (uri "*N").
    struct ImageRef {
        std::string file;  // absolute path; embedded: the label "<glTF path>#images[i]"
        std::shared_ptr<const EmbeddedImage> embedded;
    };
    std::optional<ImageRef> image_ref(const std::string& uri, const std::string& object);
    std::shared_ptr<const EmbeddedImage> embedded_image(unsigned n, std::string& label, const std::string& object);
    Rgb texture_mean(const std::string& uri, const std::string& object, bool srgb, bool& ok);
    template <class T, class F>
    T parsed(const std::string& key, const YAML::Node& y, F&& f) {
        return f(ParamValue(y, key, fname_, 1));
    }

    std::string path_, shown_;
    GltfOptions opt_;
    std::shared_ptr<const std::string> fname_;
    fs::path dir_;
    YAML::Node json_;
    std::map<std::string, Mat4> node_world_;  // global transform of each named node (the first of a name)
    std::map<std::string, std::vector<std::string>> notes_;
    const aiScene* scene_ = nullptr;  // while Assimp's scene is alive (read_assimp_scene's callback)
    std::map<unsigned, std::shared_ptr<const EmbeddedImage>> embedded_;  // by Assimp's "*N"
    std::set<std::string> embedded_names_;
    std::vector<std::string> note_order_;
    SceneDesc desc_;
};

void GltfImporter::read_json() {
    std::string bytes;
    try {
        bytes = gate().read(path_, FileGate::kDefaultMaxBytes, shown_);
    } catch (const FileRefused& e) {
        throw SceneError(fmt::format("{}: {}", path_, e.what()));
    }
    std::string text = bytes;
    // A .glb: a 12-byte header, then chunks (length, type); the first is the JSON.
    if (bytes.size() >= 4 && std::memcmp(bytes.data(), "glTF", 4) == 0) {
        uint32_t len = 0, type = 0;
        if (bytes.size() < 20) fail("glb", "truncated binary glTF header");
        std::memcpy(&len, bytes.data() + 12, 4);
        std::memcpy(&type, bytes.data() + 16, 4);
        if (type != 0x4E4F534Au || len > bytes.size() - 20) fail("glb", "the first chunk is not a JSON chunk that fits the file");
        text = bytes.substr(20, len);
    }
    try {
        json_ = YAML::Load(text);
    } catch (const YAML::Exception& e) {
        fail("json", fmt::format("not valid glTF JSON: {}", e.what()));
    }
    if (!json_.IsMap()) fail("json", "a glTF file holds a JSON object");
}

// A buffer or image named by uri is checked through the gate before Assimp opens it, so that a
// refusal names the key (e.g. `buffers[0].uri`); Assimp's own reads go through the same gate.
void GltfImporter::check_uris(const char* array) {
    const YAML::Node list = json_[array];
    if (!list || !list.IsSequence()) return;
    for (size_t i = 0; i < list.size(); ++i) {
        const YAML::Node u = list[i]["uri"];
        if (!u || !u.IsScalar()) continue;
        const std::string uri = u.as<std::string>();
        if (uri.rfind("data:", 0) == 0) continue;  // embedded base64: no file
        const std::string key = fmt::format("{}[{}].uri", array, i);
        if (uri.find("://") != std::string::npos) fail(key, fmt::format("'{}': only relative file uris are read", uri));
        const std::string file = uri_decode(uri);
        fs::path p = fs::path(file).is_relative() ? dir_ / file : fs::path(file);
        try {
            gate().check(fs::absolute(p).lexically_normal().string(), file);
        } catch (const FileRefused& e) {
            fail(key, e.what());
        }
    }
}

void GltfImporter::index_nodes(const aiNode* n, const Mat4& parent, int depth) {
    if (depth > 256) fail("nodes", "node hierarchy too deep");
    Mat4 m = parent * to_mat4(n->mTransformation);
    node_world_.emplace(n->mName.C_Str(), m);
    for (unsigned c = 0; c < n->mNumChildren; ++c) index_nodes(n->mChildren[c], m, depth + 1);
}

void GltfImporter::read_camera(const aiScene& s) {
    const YAML::Node cams = json_["cameras"];
    // Assimp names each camera after its node; the glTF camera's own name is in the JSON.
    int pick = s.mNumCameras > 0 ? 0 : -1;
    if (!opt_.camera.empty()) {
        pick = -1;
        std::string names;
        for (unsigned i = 0; i < s.mNumCameras; ++i) {
            std::string own = cams && i < cams.size() && cams[i]["name"] ? cams[i]["name"].as<std::string>() : "";
            if (pick < 0 && (opt_.camera == s.mCameras[i]->mName.C_Str() || opt_.camera == own)) pick = int(i);
            names += fmt::format("{}'{}'", names.empty() ? "" : ", ", s.mCameras[i]->mName.C_Str());
        }
        if (pick < 0)
            throw SceneError(fmt::format("{}: --camera {}: no such camera (the file has {})", path_, opt_.camera,
                                         names.empty() ? "none" : names));
    }
    YAML::Node y(YAML::NodeType::Map);
    YAML::Node film(YAML::NodeType::Map);
    // glTF gives an aspect ratio but no resolution: 320 pixels wide (edit the imported YAML for more).
    const int width = 320;
    double aspect = 4.0 / 3.0;
    if (pick < 0) {
        warn("cameras", "the file has no camera: Omega's default camera (at the origin, looking along +z)");
    } else {
        const aiCamera& c = *s.mCameras[pick];
        const std::string object = fmt::format("cameras[{}] '{}'", pick, c.mName.C_Str());
        auto it = node_world_.find(c.mName.C_Str());
        if (it == node_world_.end()) fail(object, "no node places this camera");
        // The node alone places a glTF camera; Assimp 5.2 also copies the node's translation into
        // aiCamera::mPosition, which is therefore not added again.
        Mat4 frame = omega_frame(it->second);
        aspect = c.mAspect > 0 ? double(c.mAspect) : 1.0;
        if (c.mOrthographicWidth > 0) {
            // xmag, ymag: half the view's width and height, which Omega's to_world scale sets.
            const double xmag = c.mOrthographicWidth, ymag = xmag / aspect;
            y["type"] = "orthographic";
            frame = frame * Mat4::scale({xmag, ymag, 1});
        } else {
            y["type"] = "perspective";
            // glTF's angle is the vertical one. Assimp 5.2 stores yfov x aspect as the horizontal
            // angle (linear, not through the tangents: 39.7 degrees for Blender's 38.55 at 4:3), so
            // the JSON's own yfov is used, and Assimp's value only undone where it is missing.
            double yfov = double(c.mHorizontalFOV) / aspect;
            if (cams && size_t(pick) < cams.size() && cams[pick]["perspective"] && cams[pick]["perspective"]["yfov"])
                yfov = cams[pick]["perspective"]["yfov"].as<double>();
            y["fov"] = yaml_number(yfov * 180 / kPi);
            y["fov_axis"] = "y";
        }
        if (c.mClipPlaneNear > 0) y["near_clip"] = yaml_number(c.mClipPlaneNear);
        y["to_world"] = matrix_node(frame);
    }
    film["width"] = width;
    film["height"] = std::max(1, int(std::lround(width / aspect)));
    y["film"] = film;
    desc_.sensor = parsed<SensorDesc>("sensor", y, [](ParamValue v) { return parse_sensor_value(v); });
    desc_.sensor.loc = {path_, 0, "cameras"};
}

void GltfImporter::read_lights(const aiScene& s) {
    const YAML::Node jl = json_["extensions"]["KHR_lights_punctual"]["lights"];
    for (unsigned i = 0; i < s.mNumLights; ++i) {
        const aiLight& l = *s.mLights[i];
        const std::string object = fmt::format("KHR_lights_punctual.lights '{}'", l.mName.C_Str());
        auto it = node_world_.find(l.mName.C_Str());
        if (it == node_world_.end()) fail(object, "no node places this light");
        const Mat4& node = it->second;
        // Assimp gives colour x intensity: candela for point and spot lights, lux for directional
        // ones. Over 683 lm/W they are W/sr and W/m^2 (docs/scene-format.md).
        Rgb power{float(l.mColorDiffuse.r / kGltfLumensPerWatt), float(l.mColorDiffuse.g / kGltfLumensPerWatt),
                  float(l.mColorDiffuse.b / kGltfLumensPerWatt)};
        YAML::Node y(YAML::NodeType::Map);
        if (l.mType == aiLightSource_POINT) {
            y["type"] = "point";
            y["position"] = vec_node(xform_point(node, {0, 0, 0}));
            y["intensity"] = rgb_node(power);
        } else if (l.mType == aiLightSource_SPOT) {
            y["type"] = "spot";
            y["to_world"] = matrix_node(omega_frame(node));
            y["intensity"] = rgb_node(power);
            const double outer = std::clamp(double(l.mAngleOuterCone) * 180 / kPi, 1e-3, 90.0);
            const double inner = std::clamp(double(l.mAngleInnerCone) * 180 / kPi, outer * 1e-3, outer);
            y["cutoff_angle"] = yaml_number(outer);
            y["beam_width"] = yaml_number(inner);
            note("spot lights fall off between the inner and outer cone linearly in angle (Omega's, Mitsuba's), not "
                 "as glTF's square of a ramp linear in cos",
                 object);
        } else if (l.mType == aiLightSource_DIRECTIONAL) {
            y["type"] = "directional";
            y["direction"] = vec_node(unit(xform_dir(node, {0, 0, -1})));
            y["irradiance"] = rgb_node(power);
        } else {
            warn(object, "light type not supported; skipped");
            continue;
        }
        for (size_t k = 0; jl && k < jl.size(); ++k)
            if (jl[k]["name"] && jl[k]["name"].as<std::string>() == l.mName.C_Str() && jl[k]["range"])
                note("a light's range is ignored: Omega's lights fall off with 1/r^2 everywhere", object);
        LightDesc d = parsed<LightDesc>(object, y, [](ParamValue v) { return parse_light_value(v); });
        d.loc = {path_, 0, object};
        desc_.lights.push_back(d);
    }
}

// A file name for an embedded image: the glTF image's name, else "image<i>", reduced to
// [A-Za-z0-9._-] so that it names a file in one folder on any system (no '/', no leading '.').
std::string image_file_stem(const std::string& name, size_t index) {
    std::string out;
    for (char c : name) {
        const bool ok = std::isalnum(static_cast<unsigned char>(c)) || c == '-' || c == '_' || (c == '.' && !out.empty());
        out += ok ? c : '_';
        if (out.size() >= 64) break;
    }
    while (!out.empty() && out.back() == '.') out.pop_back();
    return out.empty() || out.find_first_not_of('_') == std::string::npos ? fmt::format("image{}", index) : out;
}

// The extension its bytes call for: PNG and JPEG (what glTF allows) by their magic numbers,
// else Assimp's hint (from the image's mimeType).
std::string image_extension(const std::string& bytes, const char* hint) {
    if (bytes.rfind("\x89PNG\r\n\x1a\n", 0) == 0) return "png";
    if (bytes.rfind("\xff\xd8\xff", 0) == 0) return "jpg";
    std::string h;
    for (const char* p = hint; *p && h.size() < 8; ++p)
        if (std::isalnum(static_cast<unsigned char>(*p))) h += char(std::tolower(static_cast<unsigned char>(*p)));
    return h.empty() ? "bin" : h;
}

// Assimp's embedded texture N (a material's "*N") as an EmbeddedImage, made once. Assimp numbers
// the images that carry their own data (a bufferView or a data: uri) in the order of glTF's
// `images`, so the N-th of those in the JSON is glTF image i, whose name the file takes.
std::shared_ptr<const EmbeddedImage> GltfImporter::embedded_image(unsigned n, std::string& label,
                                                                  const std::string& object) {
    if (!scene_ || n >= scene_->mNumTextures || !scene_->mTextures[n])
        fail(object, fmt::format("texture '*{}': no such embedded image", n));
    size_t index = n;
    std::string json_name;
    const YAML::Node images = json_["images"];
    for (size_t i = 0, k = 0; images && images.IsSequence() && i < images.size(); ++i) {
        const YAML::Node u = images[i]["uri"];
        if (!images[i]["bufferView"] && !(u && u.IsScalar() && u.as<std::string>().rfind("data:", 0) == 0)) continue;
        if (k++ == n) {
            index = i;
            if (images[i]["name"] && images[i]["name"].IsScalar()) json_name = images[i]["name"].as<std::string>();
            break;
        }
    }
    label = fmt::format("{}#images[{}]", fs::absolute(path_).lexically_normal().string(), index);
    if (auto it = embedded_.find(n); it != embedded_.end()) return it->second;
    const aiTexture& t = *scene_->mTextures[n];
    // mHeight 0: mWidth bytes of an encoded file; otherwise raw texels, which glTF never has.
    if (t.mHeight != 0 || !t.pcData) fail(object, fmt::format("images[{}]: not an encoded (PNG or JPEG) image", index));
    auto img = std::make_shared<EmbeddedImage>();
    img->bytes.assign(reinterpret_cast<const char*>(t.pcData), t.mWidth);
    const std::string ext = image_extension(img->bytes, t.achFormatHint);
    std::string stem = image_file_stem(json_name.empty() ? t.mFilename.C_Str() : json_name, index);
    // A name that already ends in the extension ("wood.png") does not get it twice.
    if (stem.size() > ext.size() + 1 && stem.compare(stem.size() - ext.size() - 1, std::string::npos, "." + ext) == 0)
        stem.resize(stem.size() - ext.size() - 1);
    img->name = fmt::format("{}.{}", stem, ext);
    // Unique within the scene: a second image of the same name takes its index too.
    if (!embedded_names_.insert(img->name).second) {
        img->name = fmt::format("{}_{}.{}", stem, index, ext);
        embedded_names_.insert(img->name);
    }
    return embedded_[n] = img;
}

std::optional<GltfImporter::ImageRef> GltfImporter::image_ref(const std::string& uri, const std::string& object) {
    if (uri.empty()) return std::nullopt;
    ImageRef r;
    if (uri[0] == '*') {
        unsigned n = 0;
        const char* end = uri.data() + uri.size();
        if (auto [p, ec] = std::from_chars(uri.data() + 1, end, n); ec != std::errc() || p != end)
            fail(object, fmt::format("texture '{}': not an embedded image reference", uri));
        r.embedded = embedded_image(n, r.file, object);
        return r;
    }
    // Assimp hands data: uris over as "*N"; one that came through would name no file.
    if (uri.rfind("data:", 0) == 0) fail(object, "a data: uri image that Assimp did not decode");
    const std::string file = uri_decode(uri);
    fs::path p = fs::path(file).is_relative() ? dir_ / file : fs::path(file);
    r.file = p.string();
    return r;
}

// The mean of a texture's channels (linear), for the places Omega cannot texture.
Rgb GltfImporter::texture_mean(const std::string& uri, const std::string& object, bool srgb, bool& ok) {
    ok = false;
    std::optional<ImageRef> ref = image_ref(uri, object);
    if (!ref) return {1, 1, 1};
    const std::string where = fmt::format("{}: {}: ", path_, object);
    const auto& e = ref->embedded;
    ImagePixels img = e ? decode_image_bytes(e->bytes, e->name, e->name, where, "texture")
                        : decode_image(gate(), ref->file, uri_decode(uri), where, "texture");
    const size_t nc = size_t(img.channels), n = size_t(img.width) * size_t(img.height);
    double sum[3] = {0, 0, 0};
    for (size_t i = 0; i < n; ++i)
        for (size_t ch = 0; ch < 3; ++ch) {
            float v = img.data[i * nc + (nc >= 3 ? ch : 0)];
            sum[ch] += (srgb && !img.is_float) ? srgb_to_linear(v) : v;
        }
    ok = n > 0;
    if (!ok) return {1, 1, 1};
    return {float(sum[0] / double(n)), float(sum[1] / double(n)), float(sum[2] / double(n))};
}

std::string GltfImporter::read_material(const aiMaterial& m, unsigned index, std::optional<EmitterDesc>& emitter) {
    const YAML::Node jm = json_["materials"] && index < json_["materials"].size() ? json_["materials"][index] : YAML::Node();
    std::string name = m.GetName().C_Str();
    if (name.empty() || !jm) name = fmt::format("gltf_material_{}", index);  // Assimp's default material has no name
    const std::string base_name = name;
    for (int k = 2; desc_.materials.count(name); ++k) name = fmt::format("{}_{}", base_name, k);
    const std::string object = fmt::format("materials[{}] '{}'", index, m.GetName().C_Str());

    aiColor4D base(1, 1, 1, 1);
    if (m.Get(AI_MATKEY_BASE_COLOR, base) != AI_SUCCESS) m.Get(AI_MATKEY_COLOR_DIFFUSE, base);
    float metallic = 1, roughness = 1;  // glTF's defaults
    m.Get(AI_MATKEY_METALLIC_FACTOR, metallic);
    m.Get(AI_MATKEY_ROUGHNESS_FACTOR, roughness);
    Rgb colour{std::clamp(base.r, 0.f, 1.f), std::clamp(base.g, 0.f, 1.f), std::clamp(base.b, 0.f, 1.f)};

    aiString tex;
    aiTextureMapMode wrap = aiTextureMapMode_Wrap;
    std::string base_tex;
    std::optional<ImageRef> base_ref;  // the plastic's textured base colour
    if (m.GetTexture(aiTextureType_BASE_COLOR, 0, &tex) == AI_SUCCESS ||
        m.GetTexture(aiTextureType_DIFFUSE, 0, &tex) == AI_SUCCESS) {
        base_tex = tex.C_Str();
        m.Get(AI_MATKEY_MAPPINGMODE_U(aiTextureType_BASE_COLOR, 0), wrap);
    }
    // glTF's metallicRoughness texture: roughness in G, metallic in B (linear), times the factors.
    if (m.GetTexture(AI_MATKEY_GLTF_PBRMETALLICROUGHNESS_METALLICROUGHNESS_TEXTURE, &tex) == AI_SUCCESS) {
        bool ok = false;
        Rgb mr = texture_mean(tex.C_Str(), object, false, ok);
        if (ok) {
            roughness *= mr.y;
            metallic *= mr.z;
            note("a metallicRoughness texture becomes its mean (roughness x mean G, metallic x mean B): Omega's "
                 "roughness and metal/plastic choice are per material",
                 object);
        }
    }
    for (auto [type, what] : {std::pair{aiTextureType_NORMALS, "normal"}, {aiTextureType_LIGHTMAP, "occlusion"}})
        if (m.GetTexture(type, 0, &tex) == AI_SUCCESS) note(fmt::format("{} textures are ignored", what), object);
    if (aiString mode; m.Get(AI_MATKEY_GLTF_ALPHAMODE, mode) == AI_SUCCESS && std::string(mode.C_Str()) != "OPAQUE")
        note("alphaMode is ignored: surfaces are opaque", object);

    const double alpha = double(roughness) * double(roughness);  // glTF's GGX alpha = roughness^2
    YAML::Node y(YAML::NodeType::Map);
    if (metallic > 0 && metallic < 1) note("metallic between 0 and 1 is rounded: >= 0.5 a conductor, < 0.5 a plastic", object);
    if (metallic >= 0.5f) {
        // glTF's metal: Schlick's Fresnel from F0 = base colour. Omega's Fresnel-1 conductor tinted
        // by the base colour has the same normal-incidence reflectance, without the grazing rise.
        if (!base_tex.empty()) {
            bool ok = false;
            Rgb t = texture_mean(base_tex, object, true, ok);
            if (ok) {
                colour = {colour.x * t.x, colour.y * t.y, colour.z * t.z};
                note("a base colour texture on a metal becomes its mean colour (Omega textures diffuse reflectances only)",
                     object);
            }
        }
        y["type"] = "conductor";
        y["specular_reflectance"] = rgb_node(colour);
        note("metals become a conductor with Fresnel 1 tinted by the base colour (no grazing-angle rise to white)", object);
    } else {
        // glTF's dielectric: F0 = 0.04 (ior 1.5) over a Lambertian base: Omega's (rough) plastic.
        y["type"] = alpha > 0 ? "roughplastic" : "plastic";
        y["int_ior"] = "1.5";
        y["ext_ior"] = "1";
        if (alpha > 0) y["alpha"] = yaml_number(alpha);
        base_ref = image_ref(base_tex, object);
        if (base_ref) {
            YAML::Node b(YAML::NodeType::Map);
            b["type"] = "bitmap";
            // An embedded image's name stands in for the file here; its bytes replace it below.
            b["file"] = base_ref->embedded ? base_ref->embedded->name : uri_decode(base_tex);
            b["wrap"] = wrap == aiTextureMapMode_Clamp ? "clamp" : wrap == aiTextureMapMode_Mirror ? "mirror" : "repeat";
            y["diffuse_reflectance"] = b;
            if (colour.x != 1 || colour.y != 1 || colour.z != 1)
                note("a baseColorFactor other than 1 on a textured base colour is ignored", object);
        } else {
            y["diffuse_reflectance"] = rgb_node(colour);
        }
        note("dielectrics become Omega's plastic (a Fresnel coat of ior 1.5 over a diffuse base, Tungsten's model; "
             "glTF's BRDF is a sum of a GGX lobe and a Lambertian one)",
             object);
    }
    if (alpha > 0) y["distribution"] = "ggx";
    if (metallic >= 0.5f && alpha > 0) y["alpha"] = yaml_number(alpha);

    // Emission: emissiveFactor x KHR_materials_emissive_strength (Assimp 5.2 drops the latter),
    // read as radiance in W/(m^2 sr), one to one.
    aiColor4D em(0, 0, 0, 0);
    m.Get(AI_MATKEY_COLOR_EMISSIVE, em);
    double strength = 1;
    if (jm && jm["extensions"] && jm["extensions"]["KHR_materials_emissive_strength"] &&
        jm["extensions"]["KHR_materials_emissive_strength"]["emissiveStrength"])
        strength = jm["extensions"]["KHR_materials_emissive_strength"]["emissiveStrength"].as<double>();
    Rgb radiance{float(em.r * strength), float(em.g * strength), float(em.b * strength)};
    if (m.GetTexture(aiTextureType_EMISSIVE, 0, &tex) == AI_SUCCESS) {
        bool ok = false;
        Rgb t = texture_mean(tex.C_Str(), object, true, ok);
        if (ok) {
            radiance = {radiance.x * t.x, radiance.y * t.y, radiance.z * t.z};
            note("an emissive texture becomes its mean colour (area lights are uniform)", object);
        }
    }
    if (radiance.x > 0 || radiance.y > 0 || radiance.z > 0) {
        int two = 0;
        m.Get(AI_MATKEY_TWOSIDED, two);
        YAML::Node e(YAML::NodeType::Map);
        e["type"] = "area";
        e["radiance"] = rgb_node(radiance);
        e["two_sided"] = two != 0;  // a doubleSided glTF material emits on both sides
        emitter = parsed<EmitterDesc>(object + ".emissive", e, [](ParamValue v) { return parse_emitter_value(v); });
    }
    MaterialDesc md = parsed<MaterialDesc>(object, y, [&](ParamValue v) {
        return parse_material_value(v, name, desc_.warnings);
    });
    md.loc = {path_, 0, object};
    if (base_ref && base_ref->embedded && md.reflectance_texture) {
        md.reflectance_texture->embedded = base_ref->embedded;
        md.reflectance_texture->file = md.reflectance_texture->written = base_ref->file;
    }
    desc_.materials[name] = md;
    return name;
}

void GltfImporter::read_materials_and_shapes(const aiScene& s) {
    // Meshes drawn by some node, grouped by material, in material order.
    std::map<unsigned, std::vector<int>> by_material;
    std::function<void(const aiNode*, int)> visit = [&](const aiNode* n, int depth) {
        if (depth > 256) return;
        for (unsigned i = 0; i < n->mNumMeshes; ++i) {
            unsigned mi = n->mMeshes[i];
            if (mi >= s.mNumMeshes || !(s.mMeshes[mi]->mPrimitiveTypes & aiPrimitiveType_TRIANGLE)) continue;
            auto& v = by_material[s.mMeshes[mi]->mMaterialIndex];
            if (std::find(v.begin(), v.end(), int(mi)) == v.end()) v.push_back(int(mi));
        }
        for (unsigned c = 0; c < n->mNumChildren; ++c) visit(n->mChildren[c], depth + 1);
    };
    visit(s.mRootNode, 0);
    const std::string abs = fs::absolute(path_).lexically_normal().string();
    for (auto& [mat, parts] : by_material) {
        if (mat >= s.mNumMaterials) fail("meshes", "a mesh names a missing material");
        std::sort(parts.begin(), parts.end());
        ShapeDesc sh;
        sh.type = ShapeType::Mesh;
        sh.material = read_material(*s.mMaterials[mat], mat, sh.emitter);
        sh.name = sh.material;
        sh.file = abs;
        sh.written = shown_;
        sh.mesh_parts = parts;
        // Assimp turns glTF's v-down uvs into v-up ones; flipping back gives glTF's, which is also
        // the convention of Omega's bitmaps (uv (0, 0) = the image's top-left texel).
        sh.flip_tex_coords = true;
        sh.loc = {path_, 0, fmt::format("materials[{}]", mat)};
        sh.file_loc = sh.loc;
        desc_.shapes.push_back(std::move(sh));
    }
}

SceneDesc GltfImporter::run() {
    desc_.path = path_;
    read_json();
    for (const char* key : {"extensionsUsed", "extensionsRequired"}) {
        const YAML::Node ext = json_[key];
        for (size_t i = 0; ext && ext.IsSequence() && i < ext.size(); ++i) {
            const std::string e = ext[i].as<std::string>();
            if (kKnownExtensions.count(e)) continue;
            if (std::string(key) == "extensionsRequired")
                warn(fmt::format("{}[{}]", key, i), fmt::format("required extension '{}' is not supported; what it "
                                                                "changes is missing from the image", e));
            else
                warn(fmt::format("{}[{}]", key, i), fmt::format("extension '{}' is not supported and was ignored", e));
        }
    }
    check_uris("buffers");
    check_uris("images");
    MeshFileOptions mo;
    mo.written = shown_;
    read_assimp_scene(gate(), path_, {path_, 0, ""}, mo, 0, [&](const aiScene& s) {
        scene_ = &s;
        index_nodes(s.mRootNode, Mat4{}, 0);
        read_camera(s);
        read_lights(s);
        read_materials_and_shapes(s);
        scene_ = nullptr;
    });
    flush_notes();
    if (desc_.lights.empty() && std::none_of(desc_.shapes.begin(), desc_.shapes.end(), [](const ShapeDesc& sh) {
            return sh.emitter.has_value();
        }))
        desc_.warnings.push_back(fmt::format("{}: the scene has no light source; the image will be black", path_));
    desc_.files = opt_.files;
    check_scene_files(desc_);
    return std::move(desc_);
}

}  // namespace

SceneDesc import_gltf_file(const std::string& path, const GltfOptions& options) {
    try {
        return GltfImporter(path, options).run();
    } catch (const YAML::Exception& e) {
        // A JSON value of an unexpected type (a string where a number belongs).
        throw SceneError(fmt::format("{}:1: json: unexpected value: {}", path, e.what()));
    }
}

bool is_gltf_path(const std::string& path) {
    std::string ext = fs::path(path).extension().string();
    for (char& c : ext) c = char(std::tolower(static_cast<unsigned char>(c)));
    return ext == ".gltf" || ext == ".glb";
}

}  // namespace omega
