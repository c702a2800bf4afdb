// Fuzzes a job's scene together with its assets, loaded as omegad loads them: the YAML parser
// and Scene::build through a FileGate confined to the job's files/ (meshes through Assimp with
// whatever they name inside themselves, textures through OIIO).
//
// Input: the scene YAML, then any number of files, each introduced by a line "--- NAME" (NAME
// made a clean relative path). Beside files/ lie bait: a folder outside/ with a mesh, an mtl, a
// buffer and a texture, symlinks to them from inside files/, and a FIFO. Invariants, beyond
// "no crash, no exception but SceneError": nothing under outside/ is ever opened (inotify
// watches it; an O_PATH probe does not count, a read does), and no load blocks.
#include <fcntl.h>
#include <sys/inotify.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>
#include <system_error>

#include "io/file_gate.h"
#include "scene/scene.h"
#include "scene/scene_error.h"
#include "scene/scene_parser.h"

namespace fs = std::filesystem;

namespace {

struct Bait {
    fs::path root, files, outside;
    int watch = -1;
    Bait() {
        root = fs::temp_directory_path() / ("omega-fuzz-assets-" + std::to_string(::getpid()));
        fs::remove_all(root);
        files = root / "state/jobs/1/files";
        outside = root / "outside";
        fs::create_directories(outside);
        std::ofstream(outside / "tri.obj") << "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n";
        std::ofstream(outside / "evil.mtl") << "newmtl m\nKd 1 0 0\n";
        std::ofstream(outside / "t.ppm", std::ios::binary) << std::string("P6\n1 1\n255\n\xff\x00\x00", 14);
        std::ofstream(outside / "tri.bin") << std::string(42, '\0');
        ::mkfifo((outside / "pipe").c_str(), 0644);
        watch = ::inotify_init1(IN_NONBLOCK | IN_CLOEXEC);
        ::inotify_add_watch(watch, outside.c_str(), IN_OPEN | IN_ACCESS);
    }
    ~Bait() { fs::remove_all(root); }

    void reset() {
        fs::remove_all(files);
        fs::create_directories(files);
        fs::create_symlink(outside / "tri.obj", files / "abs-link.obj");
        fs::create_symlink("../../../../outside/evil.mtl", files / "rel-link.mtl");
        fs::create_symlink(outside, files / "outside-dir");
        fs::create_symlink(outside / "pipe", files / "pipe.obj");
    }
    void check_untouched() {
        char buf[4096];
        if (::read(watch, buf, sizeof buf) > 0) {
            std::fprintf(stderr, "a file outside the job was opened\n");
            std::abort();
        }
    }
};

std::string clean_name(std::string name) {
    std::string out;
    for (char c : name) out += (std::isalnum(static_cast<unsigned char>(c)) || c == '.' || c == '_' || c == '-') ? c : '_';
    if (out.empty() || out[0] == '.') out = "f" + out;
    return out.substr(0, 64);
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    static Bait bait;
    bait.reset();
    std::string input(reinterpret_cast<const char*>(data), size);
    std::string yaml;
    std::size_t pos = input.find("\n--- ");
    yaml = input.substr(0, pos);
    while (pos != std::string::npos) {
        std::size_t name_end = input.find('\n', pos + 5);
        if (name_end == std::string::npos) break;
        std::string name = clean_name(input.substr(pos + 5, name_end - pos - 5));
        std::size_t next = input.find("\n--- ", name_end);
        // An input's file replaces a bait link of the same name: written through the link, the
        // harness itself opened the file outside the job (and blocked on the FIFO's).
        std::error_code ec;
        fs::remove(bait.files / name, ec);
        std::ofstream(bait.files / name, std::ios::binary)
            << input.substr(name_end + 1, next == std::string::npos ? std::string::npos : next - name_end - 1);
        pos = next;
    }
    try {
        auto gate = omega::FileGate::confined({bait.files.string()});
        omega::SceneDesc d = omega::parse_scene_string(yaml, (bait.files / "scene.yaml").string(), gate);
        (void)omega::Scene::build(d);
    } catch (const omega::SceneError&) {
    }
    bait.check_untouched();
    return 0;
}
