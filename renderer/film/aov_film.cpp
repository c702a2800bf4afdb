#include "film/aov_film.h"

#include <stdexcept>

namespace omega {

void append_aov_tile_layers(const std::vector<AovFilm>& aovs, const Rect& r, ExrMeta& meta) {
    const size_t n = size_t(r.area());
    for (const AovFilm& a : aovs) {
        ExrMeta::Layer mean{"aov." + a.name, std::vector<float>(3 * n)};
        ExrMeta::Layer var{"aov." + a.name + ".var", std::vector<float>(3 * n)};
        size_t i = 0;
        for (int y = r.y0; y < r.y1; ++y)
            for (int x = r.x0; x < r.x1; ++x, ++i) {
                const PixelStats p = a.film.pixel(x, y);
                for (int c = 0; c < 3; ++c) {
                    mean.rgb[3 * i + size_t(c)] = float(p.mean[c]);
                    var.rgb[3 * i + size_t(c)] = float(p.var_of_mean[c]);
                }
            }
        meta.layers.push_back(std::move(mean));
        meta.layers.push_back(std::move(var));
    }
}

void append_aov_layers(const std::vector<AovFilm>& aovs, ExrMeta& meta) {
    if (aovs.empty()) return;
    append_aov_tile_layers(aovs, aovs.front().film.crop(), meta);
}

std::string format_aov_list(const std::vector<AovFilm>& aovs) {
    std::string out;
    for (const AovFilm& a : aovs) {
        if (!out.empty()) out += '\n';
        out += a.name;
        out += '=';
        out += a.expr;
    }
    return out;
}

std::vector<std::pair<std::string, std::string>> parse_aov_list(const std::string& text) {
    std::vector<std::pair<std::string, std::string>> out;
    size_t start = 0;
    while (start < text.size()) {
        size_t nl = text.find('\n', start);
        if (nl == std::string::npos) nl = text.size();
        const std::string line = text.substr(start, nl - start);
        const size_t eq = line.find('=');
        if (eq == std::string::npos) throw std::runtime_error("omega.aovs: expected NAME=EXPR, got '" + line + "'");
        out.emplace_back(line.substr(0, eq), line.substr(eq + 1));
        start = nl + 1;
    }
    return out;
}

}  // namespace omega
