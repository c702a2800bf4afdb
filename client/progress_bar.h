#pragma once
// Progress display for long work: a redrawn bar on a terminal, plain lines otherwise.
// Called from the thread that runs the command only.
#include <cstdio>
#include <string>

namespace omega {

class ProgressBar {
public:
    explicit ProgressBar(std::FILE* out);
    // fraction in [0, 1], or negative when unknown (time/error halts show elapsed instead).
    void update(double fraction, const std::string& status);
    void finish();

private:
    std::FILE* out_;
    bool tty_;
    size_t last_len_ = 0;
};

}  // namespace omega
