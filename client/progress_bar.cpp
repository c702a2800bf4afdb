#include "progress_bar.h"

#include <unistd.h>

#include <algorithm>

namespace omega {

ProgressBar::ProgressBar(std::FILE* out) : out_(out), tty_(isatty(fileno(out)) != 0) {}

void ProgressBar::update(double fraction, const std::string& status) {
    if (!tty_) {
        std::fprintf(out_, "%s\n", status.c_str());
        std::fflush(out_);
        return;
    }
    constexpr int kWidth = 30;
    std::string bar;
    if (fraction >= 0) {
        int filled = int(std::clamp(fraction, 0.0, 1.0) * kWidth + 0.5);
        bar = "[" + std::string(size_t(filled), '#') + std::string(size_t(kWidth - filled), '.') + "] ";
    }
    std::string line = bar + status;
    size_t pad = last_len_ > line.size() ? last_len_ - line.size() : 0;
    std::fprintf(out_, "\r%s%s", line.c_str(), std::string(pad, ' ').c_str());
    std::fflush(out_);
    last_len_ = line.size();
}

void ProgressBar::finish() {
    if (tty_ && last_len_ > 0) std::fprintf(out_, "\n");
    last_len_ = 0;
}

}  // namespace omega
