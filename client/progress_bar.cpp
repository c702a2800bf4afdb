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
        bar.reserve(kWidth + 3);
        bar.push_back('[');
        bar.append(size_t(filled), '#');
        bar.append(size_t(kWidth - filled), '.');
        bar.append("] ");
    }
    std::string line = std::move(bar);
    line.append(status);
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
