#pragma once
// Exit codes of `omega` and the exception remote commands throw to reach them.
#include <stdexcept>
#include <string>

namespace omega::client {

inline constexpr int kExitOk = 0;
inline constexpr int kExitInternal = 1;     // internal error, or a job that failed
inline constexpr int kExitBadInput = 2;     // usage, unreadable scene or manifest, unknown job
inline constexpr int kExitUnreachable = 3;  // daemon unreachable, or it refused the request

// A failure with the exit code it maps to. what() is the whole message, printed after "omega: ".
class ClientError : public std::runtime_error {
public:
    ClientError(int exit_code, const std::string& message, bool transient = false)
        : std::runtime_error(message), exit_code_(exit_code), transient_(transient) {}
    int exit_code() const { return exit_code_; }
    // Worth retrying later (connection lost, daemon busy or restarting); batch uses this.
    bool transient() const { return transient_; }

private:
    int exit_code_;
    bool transient_;
};

}  // namespace omega::client
