// Images embedded in glTF (a .glb's bufferView images, data: uris) are textures exactly as the
// same images beside a .gltf are: Blender's .glb and .gltf of one scene (tests/data/gltf) give the
// same description and the same texels, `omega import` writes the images beside the YAML, and the
// YAML reads them back.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <sstream>

#include "io/file_gate.h"
#include "scene/gltf_importer.h"
#include "scene/scene.h"
#include "scene/scene_parser.h"
#include "scene/scene_writer.h"
#include "scene/test_helpers.h"
#include "texture/image.h"

using namespace omega;
using omega::test::all_warnings;
using omega::test::has_warning;
using omega::test::scene_error_of;
using omega::test::TempDir;
namespace fs = std::filesystem;

namespace {

std::string data_file(const std::string& name) { return (test::source_root() / "tests/data/gltf" / name).string(); }

std::string bytes_of(const fs::path& p) {
    std::ifstream in(p, std::ios::binary);
    std::stringstream ss;
    ss << in.rdbuf();
    return ss.str();
}

std::string base64(const std::string& in) {
    static const char* k = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    std::string out;
    for (size_t i = 0; i < in.size(); i += 3) {
        uint32_t v = uint32_t(uint8_t(in[i])) << 16;
        if (i + 1 < in.size()) v |= uint32_t(uint8_t(in[i + 1])) << 8;
        if (i + 2 < in.size()) v |= uint32_t(uint8_t(in[i + 2]));
        out += k[(v >> 18) & 63];
        out += k[(v >> 12) & 63];
        out += i + 1 < in.size() ? k[(v >> 6) & 63] : '=';
        out += i + 2 < in.size() ? k[v & 63] : '=';
    }
    return out;
}

// The warnings with the scene's file name taken out, to compare a .glb's with its .gltf's.
std::vector<std::string> warnings_without(const SceneDesc& d, const std::string& file) {
    std::vector<std::string> out;
    for (std::string w : d.warnings) {
        for (size_t p; (p = w.find(file)) != std::string::npos;) w.erase(p, file.size());
        out.push_back(w);
    }
    return out;
}

// One triangle with uvs whose material has a base colour and an emissive texture, both the
// image `uri` names (a data: uri, or a file beside the glTF).
std::string textured_gltf(const std::string& uri, const std::string& image_name = "") {
    // Positions (0,0,0) (1,0,0) (0,1,0), then uvs (0,0) (1,0) (0,1): 60 bytes.
    const std::string buffer = "data:application/octet-stream;base64,"
                               "AAAAAAAAAAAAAAAAAACAPwAAAAAAAAAAAAAAAAAAgD8AAAAAAAAAAAAAAAAAAIA/AAAAAAAAAAAAAIA/";
    std::string name = image_name.empty() ? "" : R"("name": ")" + image_name + R"(", )";
    return R"({"asset": {"version": "2.0"}, "scene": 0, "scenes": [{"nodes": [0]}],
  "nodes": [{"mesh": 0}],
  "meshes": [{"primitives": [{"attributes": {"POSITION": 0, "TEXCOORD_0": 1}, "material": 0}]}],
  "materials": [{"name": "M", "emissiveFactor": [1, 1, 1], "emissiveTexture": {"index": 0},
                 "pbrMetallicRoughness": {"baseColorTexture": {"index": 0}, "metallicFactor": 0}}],
  "textures": [{"source": 0}],
  "images": [{)" + name + R"("uri": ")" + uri + R"("}],
  "accessors": [{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3",
                 "min": [0, 0, 0], "max": [1, 1, 0]},
                {"bufferView": 1, "componentType": 5126, "count": 3, "type": "VEC2"}],
  "bufferViews": [{"buffer": 0, "byteLength": 36}, {"buffer": 0, "byteOffset": 36, "byteLength": 24}],
  "buffers": [{"byteLength": 60, "uri": ")" + buffer + R"("}]})";
}

// An 8-bit RGB PNG claiming `w` x `h`: its signature, IHDR and an empty IDAT (libpng reads the
// header up to the first IDAT; no texel follows).
std::string png_header(uint32_t w, uint32_t h) {
    auto be = [](uint32_t v) { return std::string{char(v >> 24), char(v >> 16), char(v >> 8), char(v)}; };
    auto chunk = [&](const std::string& type_and_data) {
        uint32_t crc = 0xFFFFFFFFu;  // the PNG's CRC-32 over type and data
        for (unsigned char c : type_and_data) {
            crc ^= c;
            for (int k = 0; k < 8; ++k) crc = (crc >> 1) ^ (0xEDB88320u & (0u - (crc & 1u)));
        }
        return be(uint32_t(type_and_data.size() - 4)) + type_and_data + be(~crc);
    };
    return std::string("\x89PNG\r\n\x1a\n", 8) + chunk("IHDR" + be(w) + be(h) + std::string("\x08\x02\x00\x00\x00", 5)) +
           chunk("IDAT") + chunk("IEND");
}

}  // namespace

// Blender's .glb carries checker.png and roughness.png inside; it imports to what the .gltf beside
// the same two files imports to, the textured base colour included, and says nothing about them.
TEST(GltfEmbedded, GlbGivesTheSameSceneAsItsGltf) {
    SceneDesc a = import_gltf_file(data_file("blender_scene.gltf"));
    SceneDesc b = import_gltf_file(data_file("blender_scene.glb"));
    EXPECT_FALSE(has_warning(b, "embedded")) << all_warnings(b);
    EXPECT_EQ(warnings_without(a, "blender_scene.gltf"), warnings_without(b, "blender_scene.glb"));
    EXPECT_EQ(a.sensor.to_world.m, b.sensor.to_world.m);
    EXPECT_EQ(b.lights.size(), 3u);
    EXPECT_EQ(b.shapes.size(), 4u);
    ASSERT_EQ(a.materials.size(), b.materials.size());
    for (const auto& [name, ma] : a.materials) {
        const MaterialDesc& mb = b.materials.at(name);
        EXPECT_EQ(ma.bsdf.index(), mb.bsdf.index()) << name;
        EXPECT_EQ(ma.reflectance_texture.has_value(), mb.reflectance_texture.has_value()) << name;
    }
    // The roughness image's mean (an embedded image decoded at import) sets the same alpha.
    EXPECT_EQ(std::get<PlasticBsdf>(a.materials.at("Checker").bsdf).alpha,
              std::get<PlasticBsdf>(b.materials.at("Checker").bsdf).alpha);
    const BitmapDesc& ta = *a.materials.at("Checker").reflectance_texture;
    const BitmapDesc& tb = *b.materials.at("Checker").reflectance_texture;
    EXPECT_FALSE(ta.embedded);
    ASSERT_TRUE(tb.embedded);
    EXPECT_EQ(tb.embedded->name, "checker.png");  // the glTF image's name, its format's extension
    EXPECT_EQ(tb.embedded->bytes, bytes_of(ta.file));
    EXPECT_NE(tb.file.find("blender_scene.glb#images[0]"), std::string::npos) << tb.file;
    EXPECT_EQ(ta.raw, tb.raw);
    EXPECT_EQ(ta.wrap, tb.wrap);
    // The same texels once decoded: from memory and through the gate from the file.
    auto ia = load_image(*FileGate::unconfined(), ta.file, ta.raw, "");
    auto ib = load_image_bytes(tb.embedded->bytes, tb.embedded->name, tb.raw, "");
    ASSERT_EQ(ia->texels.size(), ib->texels.size());
    EXPECT_EQ(ia->texels, ib->texels);
    EXPECT_TRUE(Scene::build(b));
}

// A scene built from the .glb reads no file by the texture's name: a confined gate that admits
// only the .glb (not checker.png beside it) builds it.
TEST(GltfEmbedded, EmbeddedImagesNeedNoFileOfTheirOwn) {
    TempDir t;
    fs::create_directories(t.path / "job");
    fs::copy_file(data_file("blender_scene.glb"), t.path / "job/s.glb");
    GltfOptions opt;
    opt.files = FileGate::confined({(t.path / "job").string()});
    SceneDesc d = import_gltf_file((t.path / "job/s.glb").string(), opt);
    ASSERT_TRUE(d.materials.at("Checker").reflectance_texture->embedded);
    EXPECT_TRUE(Scene::build(d));
}

// `omega import x.glb -o out.yaml` writes each embedded image into out_textures/ and names it
// there; the YAML parses back to the same texture, now a file, with the same texels.
TEST(GltfEmbedded, ImportWritesTheImagesBesideTheYaml) {
    TempDir t;
    SceneDesc d = import_gltf_file(data_file("blender_scene.glb"));
    const fs::path yaml = t.path / "out.yaml";
    write_scene_file(d, yaml.string());
    const fs::path png = t.path / "out_textures/checker.png";
    ASSERT_TRUE(fs::exists(png));
    EXPECT_EQ(bytes_of(png), bytes_of(data_file("checker.png")));
    // Only the image a texture uses is written (the roughness image became a mean).
    EXPECT_EQ(std::distance(fs::directory_iterator(t.path / "out_textures"), fs::directory_iterator()), 1);
    EXPECT_NE(bytes_of(yaml).find(R"(file: "out_textures/checker.png")"), std::string::npos) << bytes_of(yaml);
    SceneDesc e = parse_scene_file(yaml.string());
    const BitmapDesc& te = *e.materials.at("Checker").reflectance_texture;
    EXPECT_FALSE(te.embedded);
    EXPECT_EQ(fs::path(te.file), png);
    // Writing again replaces the files it names, as it replaces the YAML.
    std::ofstream(png, std::ios::binary) << "stale";
    write_scene_file(d, yaml.string());
    EXPECT_EQ(bytes_of(png), bytes_of(data_file("checker.png")));
    EXPECT_TRUE(Scene::build(e));
}

// A data: uri image is embedded too; named "image<i>" when the glTF gives it no name. Its base
// colour texture and its emissive texture's mean are those of the same image in a file.
TEST(GltfEmbedded, DataUriImageEqualsTheSameImageInAFile) {
    TempDir t;
    const std::string png = bytes_of(data_file("checker.png"));
    t.write("checker.png", png);
    SceneDesc file = import_gltf_file(t.write("file.gltf", textured_gltf("checker.png")).string());
    SceneDesc data = import_gltf_file(t.write("data.gltf", textured_gltf("data:image/png;base64," + base64(png))).string());
    EXPECT_FALSE(has_warning(data, "embedded")) << all_warnings(data);
    const BitmapDesc& tb = *data.materials.at("M").reflectance_texture;
    ASSERT_TRUE(tb.embedded);
    EXPECT_EQ(tb.embedded->name, "image0.png");
    EXPECT_EQ(tb.embedded->bytes, png);
    ASSERT_EQ(file.shapes.size(), 1u);
    ASSERT_EQ(data.shapes.size(), 1u);
    ASSERT_TRUE(file.shapes[0].emitter && data.shapes[0].emitter);
    const Rgb ra = file.shapes[0].emitter->radiance, rb = data.shapes[0].emitter->radiance;
    EXPECT_EQ(ra.x, rb.x);
    EXPECT_EQ(ra.y, rb.y);
    EXPECT_EQ(ra.z, rb.z);
    EXPECT_LT(ra.x, 0.99f);  // the image's mean, not the factor (1, 1, 1)
    EXPECT_TRUE(Scene::build(data));
}

// Names are files in one folder whatever the glTF calls its images.
TEST(GltfEmbedded, ImageNamesAreSafeFileNames) {
    TempDir t;
    const std::string uri = "data:image/png;base64," + base64(bytes_of(data_file("checker.png")));
    for (auto [given, expect] : {std::pair{"../../etc/passwd", "_._.._etc_passwd.png"}, {"wood.png", "wood.png"},
                                 {"///", "image0.png"}, {"a b", "a_b.png"}}) {
        SceneDesc d = import_gltf_file(t.write("n.gltf", textured_gltf(uri, given)).string());
        EXPECT_EQ(d.materials.at("M").reflectance_texture->embedded->name, expect) << given;
    }
}

// Two different images of one name (a hand-made description) do not overwrite each other.
TEST(GltfEmbedded, WriterKeepsImagesOfOneNameApart) {
    TempDir t;
    SceneDesc d = import_gltf_file(data_file("blender_scene.glb"));
    MaterialDesc other = d.materials.at("Checker");
    auto img = std::make_shared<EmbeddedImage>(*other.reflectance_texture->embedded);
    img->bytes = bytes_of(data_file("roughness.png"));
    other.reflectance_texture->embedded = img;
    d.materials["Other"] = other;
    std::vector<EmbeddedFile> files = embedded_files(d, "x_textures");
    ASSERT_EQ(files.size(), 2u);
    EXPECT_EQ(files[0].rel, "x_textures/checker.png");
    EXPECT_EQ(files[1].rel, "x_textures/checker_2.png");
    write_scene_file(d, (t.path / "x.yaml").string());
    EXPECT_EQ(bytes_of(t.path / "x_textures/checker_2.png"), img->bytes);
}

// An embedded image is bounded as a file's is: its size is read from its header and refused
// before any texel is decoded.
TEST(GltfEmbedded, HugeEmbeddedImageIsRefusedBeforeDecoding) {
    TempDir t;
    auto p = t.write("huge.gltf", textured_gltf("data:image/png;base64," + base64(png_header(9000, 9000))));
    std::string err = scene_error_of([&] { import_gltf_file(p.string()); });  // the emissive mean decodes it
    EXPECT_NE(err.find("9000 x 9000 texels is larger than 8192 x 8192"), std::string::npos) << err;
    EXPECT_NE(err.find("image0.png"), std::string::npos) << err;
}
