// <include filename="..."/> in Mitsuba XML: the included file's children read in place, ids
// shared across files, messages naming the file each element was written in, and the file read
// through the scene's gate like any other.
#include <gtest/gtest.h>

#include "io/file_gate.h"
#include "scene/mitsuba_importer.h"
#include "scene/test_helpers.h"
#include "test_images.h"

using namespace omega;
using omega::test::all_warnings;
using omega::test::has_warning;
using omega::test::scene_error_of;
using omega::test::TempDir;

namespace {

constexpr const char* kLight =
    R"(<shape type="rectangle"><emitter type="area"><rgb name="radiance" value="1"/></emitter></shape>)";

std::string scene(const std::string& body) { return "<scene version=\"3.0.0\">\n" + body + "\n</scene>\n"; }

}  // namespace

TEST(MitsubaInclude, IncludedChildrenAreReadInPlaceAndShareIds) {
    TempDir dir;
    // Materials in one file, geometry that refers to them in another, the way exporters split.
    dir.write("parts/materials.xml", scene(R"(<bsdf type="diffuse" id="red"><rgb name="reflectance" value="0.5 0 0"/></bsdf>)"));
    dir.write("parts/geometry.xml",
              scene("<shape type=\"sphere\"><float name=\"radius\" value=\"2\"/><ref id=\"red\"/></shape>\n" +
                    std::string(kLight)));
    auto xml = dir.write("scene.xml", scene(R"(<shape type="sphere"><float name="radius" value="1"/></shape>
<include filename="parts/materials.xml"/>
<include filename="parts/geometry.xml"/>
<shape type="sphere"><float name="radius" value="3"/></shape>)"));
    SceneDesc d = import_mitsuba_file(xml.string());
    // Order is the document order with each include expanded where it stands.
    ASSERT_EQ(d.shapes.size(), 4u) << all_warnings(d);
    EXPECT_FLOAT_EQ(d.shapes[0].radius, 1.f);
    EXPECT_FLOAT_EQ(d.shapes[1].radius, 2.f);
    EXPECT_EQ(d.shapes[2].type, ShapeType::Rectangle);
    EXPECT_FLOAT_EQ(d.shapes[3].radius, 3.f);
    const auto* red = std::get_if<DiffuseBsdf>(&d.materials.at(d.shapes[1].material).bsdf);
    ASSERT_NE(red, nullptr);
    EXPECT_FLOAT_EQ(red->reflectance.x, 0.5f);
    EXPECT_FLOAT_EQ(red->reflectance.y, 0.f);
    EXPECT_FALSE(has_warning(d, "never used")) << all_warnings(d);
    EXPECT_FALSE(has_warning(d, "not supported")) << all_warnings(d);
}

TEST(MitsubaInclude, MessagesNameTheIncludedFileAndItsLine) {
    TempDir dir;
    dir.write("inc.xml", scene("\n\n<shape type=\"sphere\"><float name=\"wobble\" value=\"1\"/></shape>\n" + std::string(kLight)));
    auto xml = dir.write("scene.xml", scene(R"(<include filename="inc.xml"/>)"));
    SceneDesc d = import_mitsuba_file(xml.string());
    EXPECT_TRUE(has_warning(d, "inc.xml:4: shape[0]")) << all_warnings(d);
    EXPECT_TRUE(has_warning(d, "wobble")) << all_warnings(d);

    dir.write("bad.xml", scene("\n<shape type=\"sphere\"><float name=\"radius\" value=\"x\"/></shape>"));
    auto bad = dir.write("bad_scene.xml", scene(R"(<include filename="bad.xml"/>)"));
    std::string e = scene_error_of([&] { import_mitsuba_file(bad.string()); });
    EXPECT_NE(e.find("bad.xml:3:"), std::string::npos) << e;

    dir.write("broken.xml", "<scene version=\"3.0.0\">\n<shape>\n");
    auto broken = dir.write("broken_scene.xml", scene(R"(<include filename="broken.xml"/>)"));
    e = scene_error_of([&] { import_mitsuba_file(broken.string()); });
    EXPECT_NE(e.find("broken.xml:"), std::string::npos) << e;
    EXPECT_NE(e.find("invalid XML"), std::string::npos) << e;
}

TEST(MitsubaInclude, CyclesMissingFilesAndEscapesAreRefusedWithFileAndLine) {
    TempDir dir;
    dir.write("a.xml", scene(R"(<include filename="b.xml"/>)"));
    dir.write("b.xml", scene("\n<include filename=\"a.xml\"/>"));
    auto cyc = dir.write("cyc.xml", scene(R"(<include filename="a.xml"/>)"));
    std::string e = scene_error_of([&] { import_mitsuba_file(cyc.string()); });
    EXPECT_NE(e.find("b.xml:3: include: 'a.xml' includes itself"), std::string::npos) << e;

    auto self = dir.write("self.xml", scene("<include filename=\"self.xml\"/>"));
    e = scene_error_of([&] { import_mitsuba_file(self.string()); });
    EXPECT_NE(e.find("includes itself"), std::string::npos) << e;

    auto missing = dir.write("missing.xml", scene("\n<include filename=\"nowhere.xml\"/>"));
    e = scene_error_of([&] { import_mitsuba_file(missing.string()); });
    EXPECT_NE(e.find("missing.xml:3: include.filename:"), std::string::npos) << e;
    EXPECT_NE(e.find("nowhere.xml"), std::string::npos) << e;

    // Confined (as when a scene's files are a job's): an include that leaves the root is refused
    // like any other file, and a FIFO is never opened.
    TempDir root;
    dir.write("secret.xml", scene(kLight));
    MitsubaOptions opt;
    opt.files = FileGate::confined({root.path.string()});
    for (const std::string& ref : {(dir.path / "secret.xml").string(), std::string("../secret.xml"), std::string("/dev/zero")}) {
        e = scene_error_of([&] {
            import_mitsuba_string(scene("<include filename=\"" + ref + "\"/>"), (root.path / "scene.xml").string(), opt);
        });
        EXPECT_NE(e.find("scene.xml:2: include.filename:"), std::string::npos) << ref << ": " << e;
        EXPECT_NE(e.find("'" + ref + "' is not a submitted asset"), std::string::npos) << e;  // as written, one message
    }
}

TEST(MitsubaInclude, FilesNamedInAnIncludedFileResolveAgainstTheMainScenesFolder) {
    TempDir dir;
    test::write_image_f32((dir.path / "sky.exr").string(), 2, 2, 3, std::vector<float>(12, 1.f));
    dir.write("tri.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
    // As Mitsuba's file resolver does: relative to the scene file's folder, not the included one's.
    dir.write("parts/lights.xml", scene(R"(<emitter type="envmap"><string name="filename" value="sky.exr"/></emitter>
<shape type="obj"><string name="filename" value="tri.obj"/></shape>)"));
    auto xml = dir.write("scene.xml", scene(R"(<include filename="parts/lights.xml"/>)"));
    SceneDesc d = import_mitsuba_file(xml.string());
    ASSERT_EQ(d.lights.size(), 1u) << all_warnings(d);
    EXPECT_EQ(std::filesystem::path(d.lights[0].file).lexically_normal(), (dir.path / "sky.exr").lexically_normal());
    ASSERT_EQ(d.shapes.size(), 1u);
    EXPECT_EQ(std::filesystem::path(d.shapes[0].file).lexically_normal(), (dir.path / "tri.obj").lexically_normal());
}
