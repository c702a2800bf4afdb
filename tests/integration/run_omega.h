#pragma once
// The omega binary (OMEGA_BIN, set by tests/CMakeLists.txt) run as a user runs it, for the
// integration tests that drive the command line.
#include <sys/wait.h>

#include <array>
#include <cstdio>
#include <string>

namespace omega::test {

struct OmegaResult {
    int code = -1;
    std::string output;  // stdout and stderr
};

// `command` through the shell, stderr merged into stdout.
inline OmegaResult run_shell(const std::string& command) {
    OmegaResult r;
    FILE* p = popen((command + " 2>&1").c_str(), "r");
    if (!p) return r;
    std::array<char, 4096> buf;
    size_t n;
    while ((n = fread(buf.data(), 1, buf.size(), p)) > 0) r.output.append(buf.data(), n);
    int status = pclose(p);
    r.code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
    return r;
}

// `omega ARGS` through the shell, stderr merged into stdout.
inline OmegaResult run_omega(const std::string& args) { return run_shell(std::string(OMEGA_BIN) + " " + args); }

}  // namespace omega::test
