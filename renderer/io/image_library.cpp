#include "io/image_library.h"

#include <dlfcn.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <mutex>
#include <stdexcept>
#include <vector>

namespace omega {

namespace {

constexpr const char* kModuleName = "libomega_images.so";

// Whether `file` lies under `dir`, after resolving links in both (the build dir may be reached
// through a link, /proc/self/exe never is).
[[maybe_unused]] bool inside(const std::filesystem::path& file, const char* dir) {
    std::error_code ec;
    const std::filesystem::path d = std::filesystem::weakly_canonical(dir, ec);
    if (ec || d.empty()) return false;
    const auto rel = file.lexically_relative(d);
    return !rel.empty() && *rel.begin() != "..";
}

std::vector<std::string> candidates() {
    // Set, it is the only place looked: a deployment that names its module gets that one or an error.
    if (const char* env = std::getenv("OMEGA_IMAGE_LIBRARY"); env && *env) return {env};
    std::vector<std::string> paths;
    std::error_code ec;
    const std::filesystem::path exe = std::filesystem::read_symlink("/proc/self/exe", ec);
    if (!ec) {
        paths.push_back((exe.parent_path() / kModuleName).string());
        paths.push_back((exe.parent_path() / ".." / "lib" / "omega" / kModuleName).string());
    }
#if defined(OMEGA_IMAGE_LIBRARY_BUILT) && defined(OMEGA_BUILD_DIR)
    // The build tree's module, for the programs and tests in that build tree only: an installed
    // program must not reach into a directory that was only meant to exist on the build machine.
    if (!ec && inside(exe, OMEGA_BUILD_DIR)) paths.emplace_back(OMEGA_IMAGE_LIBRARY_BUILT);
#endif
    return paths;
}

struct Loaded {
    const ImageLibrary* table = nullptr;
    std::string error;
};

Loaded load() {
    std::string tried;
    for (const std::string& path : candidates()) {
        struct stat st {};
        if (::stat(path.c_str(), &st) != 0) {
            tried += "\n  " + path + ": not there";
            continue;
        }
        // Its code runs inside omegad: a module someone else could have replaced is not loaded.
        if ((st.st_mode & (S_IWGRP | S_IWOTH)) != 0 || (st.st_uid != 0 && st.st_uid != ::geteuid())) {
            tried += "\n  " + path + ": writable by others or owned by another user, refused";
            continue;
        }
        // Never closed: its code stays in use for the life of the process.
        void* handle = ::dlopen(path.c_str(), RTLD_NOW | RTLD_LOCAL);
        if (!handle) {
            const char* e = ::dlerror();
            tried += "\n  " + path + ": " + (e ? e : "dlopen failed");
            continue;
        }
        auto entry = reinterpret_cast<const ImageLibrary* (*)()>(::dlsym(handle, "omega_image_library"));
        const ImageLibrary* table = entry ? entry() : nullptr;
        if (!table || table->abi != kImageLibraryAbi) {
            tried += "\n  " + path + ": from another build of omega (interface " + std::to_string(table ? table->abi : 0) +
                     ", this one needs " + std::to_string(kImageLibraryAbi) + ")";
            continue;
        }
        return {table, {}};
    }
    return {nullptr, std::string("cannot load the image library ") + kModuleName +
                         " (OpenImageIO, for textures, environment maps and image files); tried:" + tried};
}

}  // namespace

const ImageLibrary& image_library() {
    static std::once_flag once;
    static Loaded loaded;
    std::call_once(once, [] { loaded = load(); });
    if (!loaded.table) throw std::runtime_error(loaded.error);
    return *loaded.table;
}

}  // namespace omega
