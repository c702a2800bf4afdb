// Every loader reads through the scene's FileGate: what a mesh file names inside itself (OBJ
// mtllib, glTF buffers), bitmap textures, Mitsuba envmaps, in both the YAML and the Mitsuba XML
// paths. A confined gate refuses what lies outside its roots with one message, never opens a
// FIFO, and a refusal leaves no descriptor behind.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <filesystem>
#include <thread>

#include "io/file_gate.h"
#include "scene/mitsuba_importer.h"
#include "scene/scene.h"
#include "scene/scene_parser.h"
#include "scene/test_helpers.h"
#include "scene/triangle_mesh.h"
#include "test_images.h"
#include "texture/image.h"

namespace omega {
namespace {

namespace fs = std::filesystem;

const char* kRefused = "is not a submitted asset or a regular file under an allowed root";

int open_fds() {
    int n = 0;
    for (auto it = fs::directory_iterator("/proc/self/fd"); it != fs::directory_iterator(); ++it) ++n;
    return n;
}

const char* kTriangle = "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n";

// A glTF with one triangle whose buffer is `uri`, `bytes` long.
std::string gltf_with_buffer(const std::string& uri, int bytes = 42) {
    return R"({"asset":{"version":"2.0"},"scenes":[{"nodes":[0]}],"nodes":[{"mesh":0}],
"meshes":[{"primitives":[{"attributes":{"POSITION":0},"indices":1}]}],
"buffers":[{"uri":")" + uri + R"(","byteLength":)" + std::to_string(bytes) + R"(}],
"bufferViews":[{"buffer":0,"byteOffset":0,"byteLength":36},{"buffer":0,"byteOffset":36,"byteLength":6}],
"accessors":[{"bufferView":0,"componentType":5126,"count":3,"type":"VEC3","min":[0,0,0],"max":[1,1,0]},
{"bufferView":1,"componentType":5123,"count":3,"type":"SCALAR"}]})";
}

std::string triangle_buffer() {
    const float p[9] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
    const uint16_t i[3] = {0, 1, 2};
    std::string b(reinterpret_cast<const char*>(p), sizeof p);
    b.append(reinterpret_cast<const char*>(i), sizeof i);
    return b;
}

struct Job {
    test::TempDir dir;
    fs::path files, outside;
    std::shared_ptr<const FileGate> gate;
    Job() {
        files = dir.path / "state/jobs/1/files";
        outside = dir.path / "outside";
        fs::create_directories(files);
        dir.write("outside/evil.mtl", "newmtl m\nKd 1 0 0\n");
        dir.write("outside/tri.bin", triangle_buffer());
        dir.write("outside/tri.obj", kTriangle);
        gate = FileGate::confined({files.string()});
    }
    fs::path put(const std::string& name, const std::string& text) const { return dir.write("state/jobs/1/files/" + name, text); }
    TriangleMesh load(const fs::path& p) const { return load_mesh_file(*gate, p.string(), {"scene.yaml", 3, "shapes[0].file"}); }
};

TEST(FileConfinement, ObjMtllibOutsideRefusesTheMesh) {
    Job j;
    for (const std::string& ref : std::vector<std::string>{"../../../../outside/evil.mtl", (j.outside / "evil.mtl").string(), "/proc/self/environ"}) {
        auto obj = j.put("m.obj", "mtllib " + ref + "\n" + kTriangle);
        std::string e = test::scene_error_of([&] { j.load(obj); });
        EXPECT_NE(e.find(kRefused), std::string::npos) << ref << ": " << e;
        EXPECT_EQ(e.find(j.dir.path.string()), std::string::npos) << e;
    }
    // Inside the job, the same mtllib is read.
    j.put("ok.mtl", "newmtl m\nKd 1 0 0\n");
    EXPECT_EQ(j.load(j.put("m.obj", std::string("mtllib ok.mtl\n") + kTriangle)).triangle_count(), 1u);
}

TEST(FileConfinement, GltfBufferOutsideRefusesTheMesh) {
    Job j;
    j.put("tri.bin", triangle_buffer());
    EXPECT_EQ(j.load(j.put("ok.gltf", gltf_with_buffer("tri.bin"))).triangle_count(), 1u);
    for (const std::string& uri : std::vector<std::string>{"../../../../outside/tri.bin", (j.outside / "tri.bin").string()}) {
        std::string e = test::scene_error_of([&] { j.load(j.put("m.gltf", gltf_with_buffer(uri))); });
        EXPECT_NE(e.find(kRefused), std::string::npos) << uri << ": " << e;
    }
}

TEST(FileConfinement, FifoNamedByAMeshIsNeverOpened) {
    Job j;
    const fs::path fifo = j.outside / "pipe.mtl";
    ASSERT_EQ(::mkfifo(fifo.c_str(), 0644), 0);
    ASSERT_EQ(::mkfifo((j.files / "pipe.mtl").c_str(), 0644), 0);
    std::atomic<bool> opened{false};
    std::thread writer([&] {
        int fd = ::open(fifo.c_str(), O_WRONLY | O_CLOEXEC);
        opened = true;
        if (fd >= 0) ::close(fd);
    });
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
    for (const std::string& ref : {fifo.string(), std::string("pipe.mtl")}) {
        auto t0 = std::chrono::steady_clock::now();
        std::string e = test::scene_error_of([&] { j.load(j.put("m.obj", "mtllib " + ref + "\n" + kTriangle)); });
        EXPECT_NE(e.find(kRefused), std::string::npos) << e;
        EXPECT_LT(std::chrono::steady_clock::now() - t0, std::chrono::seconds(2));
    }
    EXPECT_FALSE(opened.load());
    int fd = ::open(fifo.c_str(), O_RDONLY | O_NONBLOCK | O_CLOEXEC);
    writer.join();
    ::close(fd);
}

TEST(FileConfinement, RefusedMeshesLeakNoDescriptor) {
    Job j;
    j.put("short.bin", "0123");  // shorter than its byteLength: Assimp refuses it
    auto short_gltf = j.put("short.gltf", gltf_with_buffer("short.bin", 42));
    auto outside_obj = j.put("o.obj", "mtllib ../../../../outside/evil.mtl\n" + std::string(kTriangle));
    // Assimp refuses a 3-byte .mtl ("File is too small") and forgets its stream (found by
    // fuzz_scene_assets): under ASan, a leak here fails the run.
    j.put("broken.mtl", "ne\n");
    const auto broken = j.put("b.obj", "mtllib broken.mtl\n" + std::string(kTriangle));
    EXPECT_NE(test::scene_error_of([&] { j.load(broken); }).find("cannot load mesh 'b.obj'"), std::string::npos);
    (void)test::scene_error_of([&] { j.load(short_gltf); });
    const int before = open_fds();
    for (int i = 0; i < 200; ++i) {
        EXPECT_NE(test::scene_error_of([&] { j.load(short_gltf); }), "(no SceneError)");
        EXPECT_NE(test::scene_error_of([&] { j.load(outside_obj); }), "(no SceneError)");
    }
    EXPECT_EQ(open_fds(), before);
}

TEST(FileConfinement, TexturesInEveryFormatAreDecodedFromMemory) {
    Job j;
    std::vector<uint8_t> px = {255, 0, 0, 0, 255, 0, 0, 0, 255, 128, 128, 128};
    std::vector<float> fpx = {1, 0, 0, 0, 1, 0, 0, 0, 1, 0.5f, 0.5f, 0.5f};
    for (const char* ext : {"png", "jpg", "tga", "bmp", "tif", "ppm"}) {
        test::write_image_u8((j.files / (std::string("t.") + ext)).string(), 2, 2, 3, px);
        auto img = load_image(*j.gate, (j.files / (std::string("t.") + ext)).string(), true, "");
        EXPECT_EQ(img->width, 2) << ext;
        EXPECT_NEAR(img->at(1, 1).x, 128 / 255.f, 0.05f) << ext;
    }
    // OIIO writes no PFM: one by hand (little-endian, rows bottom first; both rows alike here).
    std::vector<float> pfm_rows = {0, 0, 1, 0.5f, 0.5f, 0.5f, 1, 0, 0, 0, 1, 0};
    j.put("f.pfm", "PF\n2 2\n-1.0\n" + std::string(reinterpret_cast<const char*>(pfm_rows.data()), 48));
    for (const char* ext : {"exr", "hdr", "pfm"}) {
        if (std::string(ext) != "pfm") test::write_image_f32((j.files / (std::string("f.") + ext)).string(), 2, 2, 3, fpx);
        ImagePixels p = decode_image(*j.gate, (j.files / (std::string("f.") + ext)).string(), "", "");
        EXPECT_TRUE(p.is_float) << ext;
        EXPECT_NEAR(p.data[9], 0.5f, 0.01f) << ext;
    }
}

TEST(FileConfinement, YamlScenesNameOnlyWhatTheGateAdmits) {
    Job j;
    test::write_image_u8((j.outside / "t.png").string(), 1, 1, 3, {10, 20, 30});
    j.dir.write("outside/m.obj", kTriangle);
    const std::string virt = (j.files / "scene.yaml").string();
    for (const std::string& ref : {std::string("../../../../outside/t.png"), (j.outside / "t.png").string(),
                                   std::string("/dev/zero"), std::string("/proc/self/environ"), std::string("missing.png")}) {
        std::string yaml = "omega: 1\nmaterials:\n  m: {type: diffuse, reflectance: {type: bitmap, file: '" + ref +
                           "'}}\nshapes:\n  - {type: rectangle, material: m}\n";
        std::string e = test::scene_error_of([&] { parse_scene_string(yaml, virt, j.gate); });
        EXPECT_NE(e.find("scene.yaml:3: materials.m.reflectance.file: '" + ref + "' " + kRefused), std::string::npos)
            << e;
        yaml = "omega: 1\nmaterials:\n  m: {type: diffuse}\nshapes:\n  - {type: mesh, file: '" + ref + "', material: m}\n";
        e = test::scene_error_of([&] { parse_scene_string(yaml, virt, j.gate); });
        EXPECT_NE(e.find("scene.yaml:5: shapes[0].file: '" + ref + "' " + kRefused), std::string::npos) << e;
    }
}

TEST(FileConfinement, MitsubaScenesNameOnlyWhatTheGateAdmits) {
    Job j;
    test::write_image_u8((j.outside / "t.png").string(), 1, 1, 3, {10, 20, 30});
    test::write_image_f32((j.outside / "sky.exr").string(), 2, 1, 3, {1, 1, 1, 1, 1, 1});
    MitsubaOptions opt;
    opt.files = j.gate;
    const std::string virt = (j.files / "scene.xml").string();
    const std::string ref = "../../../../outside/";
    auto xml = [](const std::string& body) { return "<scene version=\"3.0.0\">\n" + body + "\n</scene>\n"; };
    for (const std::string& body :
         {"<shape type=\"obj\"><string name=\"filename\" value=\"" + ref + "tri.obj\"/></shape>",
          "<emitter type=\"envmap\"><string name=\"filename\" value=\"" + ref + "sky.exr\"/></emitter>",
          "<shape type=\"rectangle\"><bsdf type=\"diffuse\"><texture type=\"bitmap\" name=\"reflectance\"><string "
          "name=\"filename\" value=\"" + ref + "t.png\"/></texture></bsdf></shape>",
          "<shape type=\"rectangle\"><bsdf type=\"roughconductor\"><texture type=\"bitmap\" "
          "name=\"specular_reflectance\"><string name=\"filename\" value=\"" + ref + "t.png\"/></texture></bsdf></shape>"}) {
        std::string e = test::scene_error_of([&] { import_mitsuba_string(xml(body), virt, opt); });
        EXPECT_NE(e.find(kRefused), std::string::npos) << body << "\n" << e;
        EXPECT_NE(e.find("'" + ref), std::string::npos) << e;  // named as written
        EXPECT_EQ(e.find(j.dir.path.string(), virt.size()), std::string::npos) << e;
    }
}

TEST(FileConfinement, BuildStopsWhenCancelled) {
    Job j;
    j.put("m.obj", kTriangle);
    SceneDesc d = parse_scene_string("omega: 1\nmaterials:\n  m: {type: diffuse}\nshapes:\n  - {type: mesh, file: m.obj, material: m}\n",
                                     (j.files / "s.yaml").string(), j.gate);
    EXPECT_THROW(Scene::build(d, [] { return true; }), BuildCancelled);
    EXPECT_NO_THROW(Scene::build(d, [] { return false; }));
}

}  // namespace
}  // namespace omega
