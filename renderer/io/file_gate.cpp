#include "io/file_gate.h"

#include <fcntl.h>
#include <linux/magic.h>
#include <linux/openat2.h>
#include <sys/stat.h>
#include <sys/statfs.h>
#include <sys/syscall.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <optional>

#include <fmt/format.h>

namespace omega {

namespace fs = std::filesystem;

UniqueFd& UniqueFd::operator=(UniqueFd&& o) noexcept {
    if (this != &o) {
        if (fd_ >= 0) ::close(fd_);
        fd_ = o.release();
    }
    return *this;
}

UniqueFd::~UniqueFd() {
    if (fd_ >= 0) ::close(fd_);
}

namespace {

std::string normal_absolute(const std::string& path) {
    std::error_code ec;
    fs::path p = fs::absolute(fs::path(path), ec);
    if (ec) p = fs::path(path);
    std::string s = p.lexically_normal().string();
    while (s.size() > 1 && s.back() == '/') s.pop_back();
    return s;
}

// The remainder of `path` beneath `root` ("" for the root itself), or nullopt.
std::optional<std::string> beneath(const std::string& path, const std::string& root) {
    if (root == "/") return path == "/" ? std::string() : path.substr(1);
    if (path == root) return std::string();
    if (path.size() > root.size() && path.compare(0, root.size(), root) == 0 && path[root.size()] == '/')
        return path.substr(root.size() + 1);
    return std::nullopt;
}

// Kernel views of processes, devices and settings: their "regular" files are not data.
bool pseudo_filesystem(int fd) {
    struct statfs s {};
    if (::fstatfs(fd, &s) != 0) return true;
    switch (static_cast<unsigned long>(s.f_type)) {
        case PROC_SUPER_MAGIC: case SYSFS_MAGIC: case DEBUGFS_MAGIC: case TRACEFS_MAGIC:
        case SECURITYFS_MAGIC: case CGROUP_SUPER_MAGIC: case CGROUP2_SUPER_MAGIC: case BPF_FS_MAGIC:
        case DEVPTS_SUPER_MAGIC: case EFIVARFS_MAGIC: case PSTOREFS_MAGIC:
            return true;
        default:
            return false;
    }
}

// openat2(dir, rel, flags) kept beneath `dir`; -1 with errno. ENOSYS where the kernel (or a
// seccomp filter) lacks openat2.
int open_beneath_kernel(int dir, const std::string& rel, int flags) {
    struct open_how how {};
    how.flags = static_cast<std::uint64_t>(flags);
    how.resolve = RESOLVE_BENEATH | RESOLVE_NO_MAGICLINKS;
    return static_cast<int>(::syscall(SYS_openat2, dir, rel.c_str(), &how, sizeof how));
}

}  // namespace

int detail::open_beneath_walk(int dir, const std::string& rel, int flags) {
    UniqueFd cur(::fcntl(dir, F_DUPFD_CLOEXEC, 0));
    if (!cur) return -1;
    std::size_t start = 0;
    while (true) {
        std::size_t slash = rel.find('/', start);
        const bool last = slash == std::string::npos;
        std::string comp = rel.substr(start, last ? std::string::npos : slash - start);
        if (comp.empty() || comp == "." || comp == "..") {
            errno = EXDEV;
            return -1;
        }
        const int f = last ? (flags | O_NOFOLLOW) : (O_PATH | O_DIRECTORY | O_NOFOLLOW | O_CLOEXEC);
        UniqueFd next(::openat(cur.get(), comp.c_str(), f));
        if (!next) return -1;
        if (last) return next.release();
        cur = std::move(next);
        start = slash + 1;
    }
}

namespace {

int open_beneath(int dir, const std::string& rel, int flags) {
    int fd = open_beneath_kernel(dir, rel, flags);
    if (fd < 0 && (errno == ENOSYS || errno == EPERM)) fd = detail::open_beneath_walk(dir, rel, flags);
    return fd;
}

}  // namespace

FileGate::FileGate() = default;

std::shared_ptr<const FileGate> FileGate::confined(std::vector<std::string> roots) {
    auto g = std::make_shared<FileGate>();
    g->confined_ = true;
    for (auto& r : roots) {
        if (!fs::path(r).is_absolute()) throw std::invalid_argument("file gate root '" + r + "' is not absolute");
        g->roots_.push_back(normal_absolute(r));
    }
    return g;
}

std::shared_ptr<const FileGate> FileGate::unconfined() {
    static const auto g = std::make_shared<const FileGate>();
    return g;
}

std::string FileGate::shown(const std::string& path) const {
    const std::string p = normal_absolute(path);
    if (!roots_.empty())
        if (auto rel = beneath(p, roots_.front()); rel && !rel->empty()) return *rel;
    if (!confined_) return path;
    return fs::path(p).filename().string();
}

void FileGate::refuse(const std::string& path, const std::string& written, const std::string& why) const {
    const std::string name = written.empty() ? shown(path) : written;
    // One message for every refusal of a confined gate: missing, outside, symlinked out, a FIFO.
    if (confined_)
        throw FileRefused(fmt::format("'{}' is not a submitted asset or a regular file under an allowed root", name));
    throw FileRefused(fmt::format("cannot open '{}': {}", name, why));
}

UniqueFd FileGate::open_path(const std::string& path, const std::string& written, std::string& rel_out) const {
    const std::string p = normal_absolute(path);
    UniqueFd fd;
    if (confined_) {
        for (const auto& root : roots_) {
            auto rel = beneath(p, root);
            if (!rel || rel->empty()) continue;
            UniqueFd dir(::open(root.c_str(), O_PATH | O_DIRECTORY | O_CLOEXEC));
            if (!dir) continue;
            fd = UniqueFd(open_beneath(dir.get(), *rel, O_PATH | O_CLOEXEC));
            if (fd) {
                rel_out = root + "\n" + *rel;
                break;
            }
        }
        if (!fd) refuse(path, written, "outside");
    } else {
        fd = UniqueFd(::open(p.c_str(), O_PATH | O_CLOEXEC));
        if (!fd) refuse(path, written, std::strerror(errno));
        rel_out = p;
    }
    struct stat st {};
    if (::fstat(fd.get(), &st) != 0) refuse(path, written, std::strerror(errno));
    if (!S_ISREG(st.st_mode)) refuse(path, written, "not a regular file");
    if (pseudo_filesystem(fd.get())) refuse(path, written, "a file of a kernel pseudo-filesystem");
    return fd;
}

void FileGate::check(const std::string& path, const std::string& written) const {
    std::string where;
    (void)open_path(path, written, where);
}

UniqueFd FileGate::open(const std::string& path, const std::string& written) const {
    std::string where;
    UniqueFd probe = open_path(path, written, where);
    struct stat want {};
    if (::fstat(probe.get(), &want) != 0) refuse(path, written, std::strerror(errno));
    // Resolved again, now for reading; non-blocking so that a FIFO swapped in meanwhile cannot
    // block us, and refused below because it is not the file just checked.
    const int flags = O_RDONLY | O_NONBLOCK | O_CLOEXEC | O_NOCTTY;
    UniqueFd fd;
    if (confined_) {
        const auto nl = where.find('\n');
        UniqueFd dir(::open(where.substr(0, nl).c_str(), O_PATH | O_DIRECTORY | O_CLOEXEC));
        if (dir) fd = UniqueFd(open_beneath(dir.get(), where.substr(nl + 1), flags));
    } else {
        fd = UniqueFd(::open(where.c_str(), flags));
    }
    if (!fd) refuse(path, written, std::strerror(errno));
    struct stat got {};
    if (::fstat(fd.get(), &got) != 0 || !S_ISREG(got.st_mode) || got.st_dev != want.st_dev || got.st_ino != want.st_ino)
        refuse(path, written, "it changed while being opened");
    return fd;
}

std::string FileGate::read(const std::string& path, std::uint64_t max_bytes, const std::string& written) const {
    UniqueFd fd = open(path, written);
    const std::string name = written.empty() ? shown(path) : written;
    struct stat st {};
    if (::fstat(fd.get(), &st) != 0) refuse(path, written, std::strerror(errno));
    if (static_cast<std::uint64_t>(st.st_size) > max_bytes)
        throw FileRefused(fmt::format("'{}' is larger than {} bytes", name, max_bytes));
    std::string out;
    out.resize(static_cast<std::size_t>(st.st_size));
    std::size_t got = 0;
    while (true) {
        if (got == out.size()) {
            if (out.size() >= max_bytes + 1) break;  // grew past the limit while being read
            out.resize(std::min<std::uint64_t>(max_bytes + 1, out.size() + 65536));
        }
        const ssize_t n = ::read(fd.get(), out.data() + got, out.size() - got);
        if (n < 0 && errno == EINTR) continue;
        if (n < 0) throw FileRefused(fmt::format("cannot read '{}': {}", name, std::strerror(errno)));
        if (n == 0) break;
        got += static_cast<std::size_t>(n);
    }
    if (got > max_bytes) throw FileRefused(fmt::format("'{}' is larger than {} bytes", name, max_bytes));
    out.resize(got);
    return out;
}

}  // namespace omega
