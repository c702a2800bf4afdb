// submit, status, list, cancel, fetch and connection failures against a scripted fake daemon.
#include <gtest/gtest.h>

#include <map>
#include <mutex>

#include "asset_scan.h"
#include "scene/gltf_importer.h"
#include "scene/scene_writer.h"
#include "shared_data.h"
#include "job_commands.h"
#include "submit_command.h"
#include "test_fake_daemon.h"

namespace omega::client {
namespace {

namespace proto = omega::protocol;
using test::FakeDaemon;
using test::TempDir;
namespace fs = std::filesystem;

const char* kTri = "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n";
const char* kQuad = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3 4\n";

// A scene with one mesh inside its folder and one outside it (renamed by the scan).
fs::path write_scene(const TempDir& d) {
    d.write("scene/meshes/tri.obj", kTri);
    d.write("shared/quad.obj", kQuad);
    return d.write("scene/bunny.yaml", "omega: 1\n# two meshes\nshapes:\n  - {type: mesh, file: meshes/tri.obj}\n"
                                       "  - {type: mesh, file: ../shared/quad.obj}\n"
                                       "lights: [{type: constant, radiance: 1}]\n");
}

proto::JobInfo job_info(uint64_t job, proto::JobState s) {
    proto::JobInfo i;
    i.job = job;
    i.name = "bunny";
    i.state = s;
    i.priority = 5;
    i.owner = "1000";
    i.halt.spp = 64;
    i.progress.pass = 3;
    i.progress.spp = 12;
    i.progress.elapsed_s = 4.25;
    i.progress.rel_error = 0.031;
    i.progress.samples_per_s = 1.5e6;
    return i;
}

TEST(AssetScan, NamesAssetsAsTheSceneDoesAndRewritesOutsidePaths) {
    TempDir d;
    const auto scene = write_scene(d);
    ScannedScene s = scan_scene(scene.string());
    EXPECT_EQ(s.name, "bunny");
    ASSERT_EQ(s.assets.size(), 2u);
    EXPECT_EQ(s.assets[0].name, "meshes/tri.obj");
    EXPECT_EQ(s.assets[0].sha256, sha256_bytes(kTri));
    EXPECT_EQ(s.assets[0].size, std::string(kTri).size());
    // echo -n "" | sha256sum
    EXPECT_EQ(sha256_bytes(""), "e3b0c44298fc1c149afbf4c8996fb92427ae41e4649b934ca495991b7852b855");
    const std::string q = sha256_bytes(kQuad);
    EXPECT_EQ(s.assets[1].name, "assets/" + q.substr(0, 16) + "/quad.obj");
    EXPECT_NE(s.yaml.find(s.assets[1].name), std::string::npos);
    EXPECT_EQ(s.yaml.find("../shared"), std::string::npos);
    // What travels still parses, with the assets laid out under their names.
    TempDir remote;
    remote.write(s.assets[0].name, kTri);
    remote.write(s.assets[1].name, kQuad);
    const auto rs = remote.write("scene.yaml", s.yaml);
    EXPECT_NO_THROW(scan_scene(rs.string()));
}

TEST(AssetScan, UnchangedYamlWhenEveryPathIsClean) {
    TempDir d;
    d.write("meshes/tri.obj", kTri);
    const std::string yaml = "omega: 1\nshapes: [{type: mesh, file: meshes/tri.obj}]  # comment kept\n";
    ScannedScene s = scan_scene(d.write("s.yaml", yaml).string());
    EXPECT_EQ(s.yaml, yaml);
}

TEST(AssetScan, BadSceneIsBadInputWithFileAndLine) {
    TempDir d;
    const auto p = d.write("bad.yaml", "omega: 1\nshapes:\n  - {type: mesh, file: missing.obj}\n");
    try {
        scan_scene(p.string());
        FAIL();
    } catch (const ClientError& e) {
        EXPECT_EQ(e.exit_code(), kExitBadInput);
        EXPECT_NE(std::string(e.what()).find(p.string() + ":3:"), std::string::npos) << e.what();
    }
}

TEST(AssetScan, BitmapTexturesTravelAsAssets) {
    TempDir d;
    d.write("scene/textures/wood.png", "png bytes");
    d.write("shared/stone.png", "other bytes");
    const auto scene = d.write("scene/s.yaml", "omega: 1\nmaterials:\n"
                                               "  wood: {type: diffuse, reflectance: {type: bitmap, file: textures/wood.png}}\n"
                                               "shapes:\n  - {type: rectangle, material: wood}\n"
                                               "  - {type: cube, material: {type: diffuse, reflectance: {type: bitmap, "
                                               "file: ../shared/stone.png}}}\n"
                                               "  - {type: sphere, material: {type: diffuse, reflectance: {type: bitmap, "
                                               "file: textures/wood.png}}}\n");
    ScannedScene s = scan_scene(scene.string());
    ASSERT_EQ(s.assets.size(), 2u);  // wood.png once, though two materials name it
    EXPECT_EQ(s.assets[0].name, "textures/wood.png");
    EXPECT_EQ(s.assets[0].sha256, sha256_bytes("png bytes"));
    EXPECT_EQ(s.assets[1].name, "assets/" + sha256_bytes("other bytes").substr(0, 16) + "/stone.png");
    EXPECT_EQ(s.yaml.find("../shared"), std::string::npos) << s.yaml;
}

// Every parameter that takes a bitmap (a conductor's specular_reflectance, a mask's opacity, a
// bump map, a plastic's diffuse_reflectance) and the envmap's image travel; a checkerboard names
// no file. The envmap outside the scene's folder is renamed like any other asset.
TEST(AssetScan, EveryTextureAndTheEnvmapTravel) {
    TempDir d;
    for (const char* f : {"scene/t/spec.png", "scene/t/alpha.png", "scene/t/height.png", "scene/t/base.png"})
        d.write(f, std::string("bytes of ") + f);
    d.write("skies/sky.exr", "sky bytes");
    const auto scene = d.write(
        "scene/s.yaml",
        "omega: 1\nmaterials:\n"
        "  metal: {type: conductor, specular_reflectance: {type: bitmap, file: t/spec.png}}\n"
        "  leaf: {type: diffuse, opacity: {type: bitmap, file: t/alpha.png}, bump: {type: bitmap, file: t/height.png}}\n"
        "  coat: {type: plastic, diffuse_reflectance: {type: bitmap, file: t/base.png}}\n"
        "  checks: {type: diffuse, reflectance: {type: checkerboard}}\n"
        "shapes:\n  - {type: rectangle, material: metal}\n  - {type: rectangle, material: leaf}\n"
        "  - {type: rectangle, material: coat}\n  - {type: rectangle, material: checks}\n"
        "lights:\n  - {type: envmap, file: ../skies/sky.exr}\n");
    ScannedScene s = scan_scene(scene.string());
    std::map<std::string, std::string> got;
    for (const auto& a : s.assets) got[a.name] = a.sha256;
    EXPECT_EQ(got.size(), 5u);
    for (const char* f : {"t/spec.png", "t/alpha.png", "t/height.png", "t/base.png"})
        EXPECT_EQ(got[f], sha256_bytes(std::string("bytes of scene/") + f)) << f;
    const std::string sky = "assets/" + sha256_bytes("sky bytes").substr(0, 16) + "/sky.exr";
    EXPECT_EQ(got[sky], sha256_bytes("sky bytes"));
    EXPECT_NE(s.yaml.find(sky), std::string::npos) << s.yaml;
}

// A Mitsuba XML scene is imported by the client and travels as YAML, with its bitmap and envmap.
TEST(AssetScan, MitsubaSceneTravelsAsYamlWithItsFiles) {
    TempDir d;
    d.write("scene/tex/wood.png", "wood");
    d.write("scene/sky.exr", "sky");
    const auto scene = d.write("scene/s.xml", R"(<scene version="3.0.0">
<shape type="rectangle"><bsdf type="diffuse"><texture type="bitmap" name="reflectance">
  <string name="filename" value="tex/wood.png"/></texture></bsdf></shape>
<emitter type="envmap"><string name="filename" value="sky.exr"/></emitter>
</scene>)");
    ScannedScene s = scan_scene(scene.string());
    EXPECT_NE(s.yaml.find("omega: 1"), std::string::npos) << s.yaml;
    std::map<std::string, std::string> got;
    for (const auto& a : s.assets) got[a.name] = a.sha256;
    ASSERT_EQ(got.size(), 2u) << s.yaml;
    EXPECT_EQ(got["tex/wood.png"], sha256_bytes("wood"));
    EXPECT_EQ(got["sky.exr"], sha256_bytes("sky"));
}

TEST(AssetScan, FilesAMeshNamesTravelBesideIt) {
    TempDir d;
    d.write("scene/meshes/m.obj", std::string("mtllib m.mtl\n") + kTri);
    d.write("scene/meshes/m.mtl", "newmtl a\nKd 1 0 0\n");
    d.write("shared/o.obj", std::string("mtllib o.mtl\n") + kTri);
    d.write("shared/o.mtl", "newmtl b\nKd 0 1 0\n");
    d.write("scene/far.obj", std::string("mtllib ../shared/o.mtl\n") + kTri);
    const auto scene = d.write("scene/s.yaml", "omega: 1\nshapes:\n  - {type: mesh, file: meshes/m.obj}\n"
                                               "  - {type: mesh, file: ../shared/o.obj}\n  - {type: mesh, file: far.obj}\n");
    ScannedScene s = scan_scene(scene.string());
    std::map<std::string, std::string> by_name;
    for (const auto& a : s.assets) by_name[a.name] = a.sha256;
    EXPECT_EQ(by_name.at("meshes/m.mtl"), sha256_bytes("newmtl a\nKd 1 0 0\n"));
    const std::string o = "assets/" + sha256_bytes(std::string("mtllib o.mtl\n") + kTri).substr(0, 16) + "/";
    EXPECT_EQ(by_name.at(o + "o.mtl"), sha256_bytes("newmtl b\nKd 0 1 0\n"));  // beside its renamed mesh
    // An mtllib outside the mesh's own folder cannot keep its relative name: not sent, and said.
    EXPECT_EQ(by_name.count("shared/o.mtl"), 0u);
    ASSERT_FALSE(s.warnings.empty());
    EXPECT_NE(s.warnings.back().find("mesh 'far.obj' names"), std::string::npos) << s.warnings.back();
}

// A glTF scene travels as the YAML `omega import` writes beside it: the .gltf its shapes name, the
// .bin buffer Assimp reads for it and the base colour texture go as assets, under their own names.
TEST(AssetScan, ImportedGltfTravelsWithItsBufferAndTexture) {
    TempDir d;
    const fs::path data = fs::path(omega::test::source_dir()) / "tests/data/gltf";
    for (const char* f : {"blender_scene.gltf", "blender_scene.bin", "checker.png", "roughness.png"})
        fs::copy_file(data / f, d.path / f);
    write_scene_file(import_gltf_file((d.path / "blender_scene.gltf").string()), (d.path / "s.yaml").string());
    ScannedScene s = scan_scene((d.path / "s.yaml").string());
    std::map<std::string, std::string> by_name;
    for (const auto& a : s.assets) by_name[a.name] = a.sha256;
    EXPECT_EQ(by_name.size(), 3u);
    for (const char* f : {"blender_scene.gltf", "blender_scene.bin", "checker.png"})
        EXPECT_EQ(by_name.at(f), sha256_file((d.path / f).string())) << f;
}

// A .glb's embedded base colour image travels as the file `omega import` would write for it,
// named in the YAML, its bytes held in memory: no such file is made, and one of that name on
// disk is not what is sent.
TEST(AssetScan, GlbEmbeddedImageTravelsFromMemory) {
    TempDir d;
    const fs::path data = fs::path(omega::test::source_dir()) / "tests/data/gltf";
    fs::copy_file(data / "blender_scene.glb", d.path / "s.glb");
    d.write("s_textures/checker.png", "not the embedded image");
    ScannedScene s = scan_scene((d.path / "s.glb").string());
    std::map<std::string, const ScannedAsset*> by_name;
    for (const auto& a : s.assets) by_name[a.name] = &a;
    ASSERT_EQ(by_name.size(), 2u) << s.yaml;
    EXPECT_EQ(by_name.at("s.glb")->sha256, sha256_file((d.path / "s.glb").string()));
    const ScannedAsset& png = *by_name.at("s_textures/checker.png");
    ASSERT_TRUE(png.data);
    EXPECT_EQ(png.sha256, sha256_file((data / "checker.png").string()));
    EXPECT_EQ(png.size, fs::file_size(data / "checker.png"));
    EXPECT_NE(s.yaml.find(R"(file: "s_textures/checker.png")"), std::string::npos) << s.yaml;
    for (const auto& w : s.warnings) EXPECT_EQ(w.find("embedded"), std::string::npos) << w;
}

TEST(Remote, UnreachableDaemonExits3NamingTheAddress) {
    TempDir d;
    JobArgs a;
    a.host = "unix:" + (d.path / "no.sock").string();
    testing::internal::CaptureStderr();
    EXPECT_EQ(run_list(a), kExitUnreachable);
    const std::string err = testing::internal::GetCapturedStderr();
    EXPECT_NE(err.find("cannot reach the daemon at " + *a.host), std::string::npos) << err;

    a.host = "tcp:127.0.0.1:1";
    a.job = 1;
    testing::internal::CaptureStderr();
    EXPECT_EQ(run_cancel(a), kExitUnreachable);
    EXPECT_NE(testing::internal::GetCapturedStderr().find("tcp:127.0.0.1:1"), std::string::npos);

    a.host = "bogus";
    testing::internal::CaptureStderr();
    EXPECT_EQ(run_status(a), kExitBadInput);
    testing::internal::GetCapturedStderr();
}

TEST(Remote, DaemonThatRefusesTheVersionExits3) {
    FakeDaemon fake([](FakeDaemon::Session&, const proto::DecodedFrame&) {}, /*refuse_hello=*/true);
    JobArgs a;
    a.host = fake.address();
    testing::internal::CaptureStderr();
    EXPECT_EQ(run_list(a), kExitUnreachable);
    const std::string err = testing::internal::GetCapturedStderr();
    EXPECT_NE(err.find(fake.address()), std::string::npos) << err;
    EXPECT_NE(err.find("versions 7..9"), std::string::npos) << err;
}

TEST(Remote, SubmitSendsOnlyTheAssetsTheDaemonLacks) {
    TempDir d;
    const auto scene = write_scene(d);
    const std::string have = sha256_bytes(kTri);  // the daemon already holds the triangle
    std::mutex mu;
    std::optional<proto::Submit> got;
    std::vector<proto::Asset> assets;
    FakeDaemon fake([&](FakeDaemon::Session& s, const proto::DecodedFrame& f) {
        std::lock_guard lock(mu);
        if (f.type == proto::MessageType::submit) {
            got = proto::decode<proto::Submit>(f).value();
            proto::NeedAssets n{f.id, {}};
            for (const auto& a : got->assets)
                if (a.sha256 != have) n.missing.push_back(a.sha256);
            s.reply(n);
        } else if (f.type == proto::MessageType::asset) {
            assets.push_back(proto::decode<proto::Asset>(f).value());
            if (assets.size() == 1) s.reply(proto::Accepted{f.id, 42});
        }
    });
    SubmitArgs a;
    a.scene = scene.string();
    a.host = fake.address();
    a.priority = 7;
    a.spp = 256;
    a.seed = 3;
    a.integrator = "bdpt";
    testing::internal::CaptureStdout();
    testing::internal::CaptureStderr();
    EXPECT_EQ(run_submit(a), kExitOk);
    const std::string out = testing::internal::GetCapturedStdout();
    const std::string err = testing::internal::GetCapturedStderr();
    EXPECT_EQ(out, "42\n") << err;  // the job id, last and alone
    EXPECT_NE(err.find("2 asset(s), 1 sent"), std::string::npos) << err;

    std::lock_guard lock(mu);
    ASSERT_TRUE(got);
    EXPECT_EQ(got->name, "bunny");
    EXPECT_EQ(got->priority, 7);
    EXPECT_EQ(got->halt.spp, 256u);
    EXPECT_FALSE(got->halt.time_s);
    EXPECT_EQ(got->seed, 3u);
    EXPECT_EQ(got->integrator, "bdpt");
    ASSERT_EQ(got->assets.size(), 2u);
    EXPECT_EQ(got->assets[0].name, "meshes/tri.obj");
    EXPECT_EQ(got->assets[0].size, std::string(kTri).size());
    EXPECT_NE(got->scene.find("meshes/tri.obj"), std::string::npos);
    ASSERT_EQ(assets.size(), 1u);  // only the quad
    EXPECT_EQ(assets[0].sha256, sha256_bytes(kQuad));
    EXPECT_EQ(assets[0].data, kQuad);
    EXPECT_EQ(assets[0].id, got->id);
}

TEST(Remote, SubmitRefusedSceneIsBadInput) {
    TempDir d;
    const auto scene = write_scene(d);
    FakeDaemon fake([&](FakeDaemon::Session& s, const proto::DecodedFrame& f) {
        if (f.type == proto::MessageType::submit) s.reply(proto::NeedAssets{f.id, {}});
        if (f.type == proto::MessageType::submit)
            s.reply(proto::Error{f.id, proto::ErrorCode::scene_invalid, "scene.yaml:4: shapes[1]: too many"});
    });
    SubmitArgs a;
    a.scene = scene.string();
    a.host = fake.address();
    testing::internal::CaptureStderr();
    EXPECT_EQ(run_submit(a), kExitBadInput);
    EXPECT_NE(testing::internal::GetCapturedStderr().find("scene.yaml:4: shapes[1]: too many"), std::string::npos);
}

TEST(Remote, StatusListCancelPauseResume) {
    std::mutex mu;
    std::vector<std::string> requests;
    FakeDaemon fake([&](FakeDaemon::Session& s, const proto::DecodedFrame& f) {
        {
            std::lock_guard lock(mu);
            requests.emplace_back(proto::to_string(f.type));
        }
        switch (f.type) {
            case proto::MessageType::status: {
                auto st = proto::decode<proto::Status>(f).value();
                if (st.job != 42) return s.reply(proto::Error{f.id, proto::ErrorCode::unknown_job, "no job 7"});
                return s.reply(proto::JobInfoReply{f.id, job_info(42, proto::JobState::running)});
            }
            case proto::MessageType::list:
                return s.reply(proto::JobList{f.id, {job_info(42, proto::JobState::running), job_info(43, proto::JobState::done)}});
            case proto::MessageType::cancel:
            case proto::MessageType::pause: return s.reply(proto::Ok{f.id});
            case proto::MessageType::resume:
                return s.reply(proto::Error{f.id, proto::ErrorCode::invalid_state, "job 42 is not paused"});
            default: return;
        }
    });
    JobArgs a;
    a.host = fake.address();
    a.job = 42;
    testing::internal::CaptureStdout();
    EXPECT_EQ(run_status(a), kExitOk);
    std::string out = testing::internal::GetCapturedStdout();
    EXPECT_NE(out.find("state     running"), std::string::npos) << out;
    EXPECT_NE(out.find("12/64 spp  4.2s  err 0.0310"), std::string::npos) << out;

    testing::internal::CaptureStdout();
    EXPECT_EQ(run_list(a), kExitOk);
    out = testing::internal::GetCapturedStdout();
    EXPECT_EQ(out.substr(0, 4), "JOB ");
    EXPECT_NE(out.find("43   done"), std::string::npos) << out;

    JobArgs all = a;
    all.job.reset();
    testing::internal::CaptureStdout();
    EXPECT_EQ(run_status(all), kExitOk);
    out = testing::internal::GetCapturedStdout();
    EXPECT_NE(out.find("2 (1 running, 1 done)"), std::string::npos) << out;
    EXPECT_NE(out.find("fake-omegad/0"), std::string::npos) << out;

    testing::internal::CaptureStdout();
    EXPECT_EQ(run_cancel(a), kExitOk);
    EXPECT_EQ(run_pause(a), kExitOk);
    out = testing::internal::GetCapturedStdout();
    EXPECT_EQ(out, "job 42 cancelled\njob 42 paused\n");

    testing::internal::CaptureStderr();
    EXPECT_EQ(run_resume(a), kExitBadInput);
    a.job = 7;
    EXPECT_EQ(run_status(a), kExitBadInput);
    const std::string err = testing::internal::GetCapturedStderr();
    EXPECT_NE(err.find("job 42 is not paused (invalid_state)"), std::string::npos) << err;
    EXPECT_NE(err.find("no job 7 (unknown_job)"), std::string::npos) << err;
}

TEST(Remote, FetchWritesTheImageBytes) {
    TempDir d;
    const std::string exr = std::string("\x76\x2f\x31\x01", 4) + "rest of an EXR file";
    FakeDaemon fake([&](FakeDaemon::Session& s, const proto::DecodedFrame& f) {
        if (f.type == proto::MessageType::fetch) s.reply(proto::Image{f.id, 42, 3, 12, 64, 48, exr});
    });
    JobArgs a;
    a.host = fake.address();
    a.job = 42;
    a.output = (d.path / "out.exr").string();
    testing::internal::CaptureStdout();
    EXPECT_EQ(run_fetch(a), kExitOk);
    EXPECT_NE(testing::internal::GetCapturedStdout().find("64x48, pass 3, 12 spp"), std::string::npos);
    EXPECT_EQ(test::slurp(a.output), exr);
    EXPECT_FALSE(fs::exists(a.output + ".tmp"));
}

}  // namespace
}  // namespace omega::client
