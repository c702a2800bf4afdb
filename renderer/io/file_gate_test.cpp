#include "io/file_gate.h"

#include <fcntl.h>
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <thread>

#include "scene/test_helpers.h"

namespace omega {
namespace {

namespace fs = std::filesystem;

void write(const fs::path& p, const std::string& text) {
    fs::create_directories(p.parent_path());
    std::ofstream(p, std::ios::binary) << text;
}

// FileRefused is a SceneError: the scene tests' helper reports it.
template <class F>
std::string refusal_of(F&& f) {
    return test::scene_error_of(std::forward<F>(f));
}

// A writer blocked in open(O_WRONLY) on a FIFO returns as soon as anyone opens it for reading:
// the witness that the gate never opened it.
struct FifoWitness {
    fs::path path;
    std::atomic<bool> opened{false};
    std::thread writer;
    explicit FifoWitness(fs::path p) : path(std::move(p)) {
        EXPECT_EQ(::mkfifo(path.c_str(), 0644), 0);
        writer = std::thread([this] {
            int fd = ::open(path.c_str(), O_WRONLY | O_CLOEXEC);
            opened = true;
            if (fd >= 0) ::close(fd);
        });
        std::this_thread::sleep_for(std::chrono::milliseconds(50));  // the writer waits in open()
    }
    ~FifoWitness() {
        int fd = ::open(path.c_str(), O_RDONLY | O_NONBLOCK | O_CLOEXEC);  // releases the writer
        writer.join();
        if (fd >= 0) ::close(fd);
    }
};

struct Layout {
    test::TempDir dir;
    fs::path files, allowed, outside;
    Layout() {
        files = dir.path / "state/jobs/1/files";
        allowed = dir.path / "allowed";
        outside = dir.path / "outside";
        write(files / "meshes/a.obj", "o a\n");
        write(allowed / "tex/b.png", "png");
        write(outside / "secret.txt", "secret");
        write(dir.path / "state/jobs/2/result.exr", "another user's image");
        fs::create_directories(files / "links");
    }
    std::shared_ptr<const FileGate> gate() const { return FileGate::confined({files.string(), allowed.string()}); }
};

TEST(FileGate, ConfinedReadsOnlyBeneathItsRoots) {
    Layout l;
    auto g = l.gate();
    EXPECT_EQ(g->read((l.files / "meshes/a.obj").string()), "o a\n");
    EXPECT_EQ(g->read((l.allowed / "tex/b.png").string()), "png");
    EXPECT_EQ(g->read((l.files / "meshes/../meshes/a.obj").string()), "o a\n");  // stays inside
    EXPECT_EQ(g->shown((l.files / "meshes/a.obj").string()), "meshes/a.obj");
}

TEST(FileGate, ConfinedRefusesEveryEscapeWithOneMessage) {
    Layout l;
    auto g = l.gate();
    const std::string msg = "'x' is not a submitted asset or a regular file under an allowed root";
    fs::create_symlink(l.outside / "secret.txt", l.files / "links/file");
    fs::create_symlink(l.outside, l.files / "links/dir");
    fs::create_symlink("../../../../../outside/secret.txt", l.files / "links/relative");
    FifoWitness fifo(l.files / "links/fifo");
    for (const std::string& path : std::vector<std::string>{
             (l.outside / "secret.txt").string(),                    // absolute, outside
             (l.files / "../../../../outside/secret.txt").string(),  // climbs out
             (l.files / "../../2/result.exr").string(),              // another job's result
             (l.files / "links/file").string(),                      // symlinked file
             (l.files / "links/dir/secret.txt").string(),            // symlinked folder
             (l.files / "links/relative").string(),                  // relative symlink out
             (l.files / "links/fifo").string(),                      // would block the opener
             (l.files / "links").string(),                           // a folder
             (l.files / "missing.obj").string(),                     // missing: the same words
             (l.outside / "missing.txt").string(),
             std::string("/proc/self/environ"), std::string("/dev/zero"), std::string("/etc/passwd")}) {
        EXPECT_EQ(refusal_of([&] { g->read(path, FileGate::kDefaultMaxBytes, "x"); }), msg) << path;
        EXPECT_EQ(refusal_of([&] { g->check(path, "x"); }), msg) << path;
    }
    EXPECT_FALSE(fifo.opened.load()) << "the gate opened a FIFO";
}

TEST(FileGate, SymlinksThatStayInsideAreFollowed) {
    Layout l;
    fs::create_symlink(l.files / "meshes/a.obj", l.files / "links/abs-inside");
    fs::create_symlink("../meshes/a.obj", l.files / "links/rel-inside");
    auto g = l.gate();
    EXPECT_EQ(g->read((l.files / "links/rel-inside").string()), "o a\n");
    // An absolute link target is an escape under RESOLVE_BENEATH, even when it points back in.
    EXPECT_NE(refusal_of([&] { g->read((l.files / "links/abs-inside").string()); }), "(no SceneError)");
}

TEST(FileGate, ShownNamesNeverHoldDaemonPaths) {
    Layout l;
    auto g = l.gate();
    EXPECT_EQ(g->shown((l.outside / "secret.txt").string()), "secret.txt");
    std::string e = refusal_of([&] { g->read((l.dir.path / "state/jobs/2/result.exr").string()); });
    EXPECT_EQ(e.find(l.dir.path.string()), std::string::npos) << e;
    EXPECT_NE(e.find("'result.exr'"), std::string::npos) << e;
}

TEST(FileGate, UnconfinedAdmitsOnlyRegularFiles) {
    Layout l;
    const FileGate& g = *FileGate::unconfined();
    EXPECT_EQ(g.read((l.outside / "secret.txt").string()), "secret");
    fs::create_symlink(l.outside / "secret.txt", l.dir.path / "link");
    EXPECT_EQ(g.read((l.dir.path / "link").string()), "secret");  // the user's own links are fine
    FifoWitness fifo(l.dir.path / "fifo");
    EXPECT_NE(refusal_of([&] { g.read(fifo.path.string()); }).find("not a regular file"), std::string::npos);
    EXPECT_NE(refusal_of([&] { g.read("/dev/zero"); }).find("not a regular file"), std::string::npos);
    EXPECT_NE(refusal_of([&] { g.read("/proc/self/environ"); }).find("pseudo-filesystem"), std::string::npos);
    EXPECT_NE(refusal_of([&] { g.read(l.dir.path.string()); }).find("not a regular file"), std::string::npos);
    EXPECT_NE(refusal_of([&] { g.read((l.dir.path / "nope").string()); }).find("No such file"), std::string::npos);
    EXPECT_FALSE(fifo.opened.load());
}

TEST(FileGate, ReadIsBounded) {
    Layout l;
    auto g = l.gate();
    EXPECT_EQ(g->read((l.files / "meshes/a.obj").string(), 4), "o a\n");
    EXPECT_NE(refusal_of([&] { g->read((l.files / "meshes/a.obj").string(), 3); }).find("larger than 3 bytes"),
              std::string::npos);
}

TEST(FileGate, WalkFallbackRefusesSymlinksAndDotDot) {
    Layout l;
    fs::create_symlink("../meshes/a.obj", l.files / "links/rel-inside");
    UniqueFd root(::open(l.files.c_str(), O_PATH | O_DIRECTORY | O_CLOEXEC));
    ASSERT_TRUE(root);
    UniqueFd ok(detail::open_beneath_walk(root.get(), "meshes/a.obj", O_RDONLY | O_CLOEXEC));
    EXPECT_TRUE(ok);
    for (const char* rel : {"links/rel-inside", "../files/meshes/a.obj", "meshes/../meshes/a.obj", "/etc/passwd"})
        EXPECT_LT(detail::open_beneath_walk(root.get(), rel, O_RDONLY | O_CLOEXEC), 0) << rel;
}

TEST(FileGate, ConfinedRootsMustBeAbsolute) {
    EXPECT_THROW(FileGate::confined({"relative/dir"}), std::invalid_argument);
}

}  // namespace
}  // namespace omega
