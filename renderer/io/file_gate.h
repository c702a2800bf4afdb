#pragma once
// The one way any scene loader reaches a file: the YAML parser and the Mitsuba importer when they
// check a name, texture and envmap decoding (through OIIO, from memory), and mesh loading
// (through Assimp, whose every open, including an OBJ's mtllib or a glTF buffer, comes here).
//
// A gate admits only regular files: never a FIFO (which would block the opener), a device
// (/dev/zero never ends), a socket, a directory, or a file of a kernel pseudo-filesystem such as
// /proc or /sys. A confined gate (omegad) also admits only files beneath one of its roots: the
// job's own files/ and the configured allowed_roots. The name is resolved by the kernel
// (openat2 with RESOLVE_BENEATH) relative to the root, so neither `..` nor a symlink can leave
// it; where openat2 is missing, a component-by-component walk refuses every symlink and `..`.
// The file is first opened O_PATH, which does not open it for I/O (a FIFO's writer is not woken),
// and only a regular file is then opened for reading, non-blocking.
//
// Refusals throw FileRefused. A confined gate says the same thing whether the file is missing,
// outside, or of the wrong kind, so a refusal tells a client nothing about the daemon's
// filesystem, and it names the file only as the scene wrote it (relative to the job's files),
// never by an absolute daemon path.
//
// Immutable after construction; any thread.
#include <cstdint>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "scene/scene_error.h"

namespace omega {

// A SceneError so that loaders that do not catch it still report bad input (exit 2,
// scene_invalid); its message holds no location, which the loader adds in front.
struct FileRefused : SceneError {
    using SceneError::SceneError;
};

// An open descriptor, closed on destruction.
class UniqueFd {
  public:
    UniqueFd() = default;
    explicit UniqueFd(int fd) : fd_(fd) {}
    UniqueFd(UniqueFd&& o) noexcept : fd_(o.release()) {}
    UniqueFd& operator=(UniqueFd&& o) noexcept;
    UniqueFd(const UniqueFd&) = delete;
    UniqueFd& operator=(const UniqueFd&) = delete;
    ~UniqueFd();
    int get() const { return fd_; }
    int release() {
        int f = fd_;
        fd_ = -1;
        return f;
    }
    explicit operator bool() const { return fd_ >= 0; }

  private:
    int fd_ = -1;
};

class FileGate {
  public:
    // Files larger than this are refused by read() unless the caller names a smaller limit.
    static constexpr std::uint64_t kDefaultMaxBytes = std::uint64_t(1) << 30;

    // Unconfined: any regular file the process may read (omega render of one's own scenes).
    FileGate();
    // Confined beneath `roots` (absolute directories; the first is the one names are shown
    // relative to, e.g. a job's files/). Throws std::invalid_argument for a relative root.
    static std::shared_ptr<const FileGate> confined(std::vector<std::string> roots);
    // The process-wide unconfined gate, shared by descriptions that were given none.
    static std::shared_ptr<const FileGate> unconfined();

    bool is_confined() const { return confined_; }

    // Checks that `path` (absolute, or relative to the working directory) names a file the gate
    // admits, without opening it for reading. `written`, when given, is the name as the scene
    // wrote it, which messages then show. Throws FileRefused.
    void check(const std::string& path, const std::string& written = {}) const;
    // Opens it for reading (O_RDONLY | O_NONBLOCK | O_CLOEXEC). Throws FileRefused.
    UniqueFd open(const std::string& path, const std::string& written = {}) const;
    // Its whole content, at most `max_bytes`. Throws FileRefused.
    std::string read(const std::string& path, std::uint64_t max_bytes = kDefaultMaxBytes,
                     const std::string& written = {}) const;

    // `path` as messages show it: relative to the first root when beneath it, else as given
    // for an unconfined gate, else only its last component (an absolute daemon path never
    // reaches a client).
    std::string shown(const std::string& path) const;

  private:
    // The O_PATH descriptor of an admitted file; `where` receives how to resolve it again.
    UniqueFd open_path(const std::string& path, const std::string& written, std::string& where) const;
    [[noreturn]] void refuse(const std::string& path, const std::string& written, const std::string& why) const;

    bool confined_ = false;
    std::vector<std::string> roots_;  // lexically normal, absolute, no trailing '/'
};

namespace detail {
// The fallback where openat2 is missing: `rel` opened beneath the directory `dir` one component
// at a time, refusing `..`, an empty component and every symlink. -1 with errno on refusal.
int open_beneath_walk(int dir, const std::string& rel, int flags);
}  // namespace detail

}  // namespace omega
