#include "breakdown_chart.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <stdexcept>
#include <vector>

#include <fmt/format.h>

#include "io/image_library.h"

namespace omega {

namespace {

// A 5 x 7 bitmap font for the few glyphs a chart needs (class names, k=, percentages), so the
// chart needs no font file: CI machines and containers often have none for OIIO's render_text.
struct Glyph {
    char c;
    std::array<uint8_t, 7> rows;  // bit 4 is the leftmost column
};
constexpr Glyph kFont[] = {
    {'0', {14, 17, 19, 21, 25, 17, 14}}, {'1', {4, 12, 4, 4, 4, 4, 14}},    {'2', {14, 17, 1, 2, 4, 8, 31}},
    {'3', {30, 1, 1, 14, 1, 1, 30}},     {'4', {2, 6, 10, 18, 31, 2, 2}},   {'5', {31, 16, 30, 1, 1, 17, 14}},
    {'6', {6, 8, 16, 30, 17, 17, 14}},   {'7', {31, 1, 2, 4, 8, 8, 8}},     {'8', {14, 17, 17, 14, 17, 17, 14}},
    {'9', {14, 17, 17, 15, 1, 2, 12}},   {'L', {16, 16, 16, 16, 16, 16, 31}}, {'S', {15, 16, 16, 14, 1, 1, 30}},
    {'D', {30, 17, 17, 17, 17, 17, 30}}, {'E', {31, 16, 16, 30, 16, 16, 31}}, {'G', {14, 17, 16, 23, 17, 17, 15}},
    {'k', {16, 16, 18, 20, 24, 20, 18}}, {'=', {0, 0, 31, 0, 31, 0, 0}},    {'%', {24, 25, 2, 4, 8, 19, 3}},
    {'>', {8, 4, 2, 1, 2, 4, 8}},        {'.', {0, 0, 0, 0, 0, 12, 12}},    {'o', {0, 0, 14, 17, 17, 17, 14}},
    {'t', {8, 8, 28, 8, 8, 9, 6}},       {'h', {16, 16, 22, 25, 17, 17, 17}}, {'e', {0, 0, 14, 17, 31, 16, 14}},
    {'r', {0, 0, 22, 25, 16, 16, 16}},
};
constexpr int kScale = 2;                 // each font pixel is 2 x 2 image pixels
constexpr int kAdvance = 6 * kScale;      // glyph width plus one column of space
constexpr int kTextHeight = 7 * kScale;

// An 8-bit RGB canvas filled here and written by ImageOutput on the calling thread: an ImageBuf
// fills and converts through OIIO's thread pool, a library TSan cannot see into (its hand-offs
// read as races in the TSan build), for a chart of a few hundred pixels.
struct Canvas {
    int width, height;
    std::vector<uint8_t> rgb;
    Canvas(int w, int h) : width(w), height(h), rgb(size_t(w) * size_t(h) * 3, 255) {}
};

void fill(Canvas& img, int x0, int y0, int x1, int y1, const std::array<float, 3>& c) {
    x0 = std::max(x0, 0), y0 = std::max(y0, 0), x1 = std::min(x1, img.width), y1 = std::min(y1, img.height);
    for (int y = y0; y < y1; ++y)
        for (int x = x0; x < x1; ++x)
            for (int k = 0; k < 3; ++k)
                img.rgb[(size_t(y) * size_t(img.width) + size_t(x)) * 3 + size_t(k)] =
                    uint8_t(std::lround(std::clamp(c[size_t(k)], 0.f, 1.f) * 255.f));
}

// Draws `text` with its top-left corner at (x, y); glyphs the font lacks are left blank.
void draw_text(Canvas& img, int x, int y, const std::string& text) {
    const std::array<float, 3> black{0.f, 0.f, 0.f};
    for (char ch : text) {
        for (const Glyph& g : kFont) {
            if (g.c != ch) continue;
            for (int r = 0; r < 7; ++r)
                for (int col = 0; col < 5; ++col)
                    if (g.rows[size_t(r)] & (16 >> col))
                        fill(img, x + col * kScale, y + r * kScale, x + (col + 1) * kScale, y + (r + 1) * kScale, black);
        }
        x += kAdvance;
    }
}

// Distinct colours for the classes carrying the most energy; the rest share grey.
constexpr std::array<std::array<float, 3>, 10> kPalette{{{0.12f, 0.47f, 0.71f},
                                                         {1.00f, 0.50f, 0.05f},
                                                         {0.17f, 0.63f, 0.17f},
                                                         {0.84f, 0.15f, 0.16f},
                                                         {0.58f, 0.40f, 0.74f},
                                                         {0.55f, 0.34f, 0.29f},
                                                         {0.89f, 0.47f, 0.76f},
                                                         {0.74f, 0.74f, 0.13f},
                                                         {0.09f, 0.75f, 0.81f},
                                                         {0.30f, 0.30f, 0.30f}}};
constexpr std::array<float, 3> kOther{0.75f, 0.75f, 0.75f};

}  // namespace

void write_breakdown_chart(const BreakdownReport& r, const std::string& path) {
    const auto classes = r.of_kind("class");
    const auto lengths = r.of_kind("length");
    // The classes by fraction, largest first: the first ones get the palette and the legend.
    std::vector<const BreakdownRow*> ranked = classes;
    std::stable_sort(ranked.begin(), ranked.end(), [](auto* a, auto* b) { return a->fraction > b->fraction; });
    std::map<std::string, size_t> colour;  // class name -> palette index
    for (size_t i = 0; i < ranked.size() && i < kPalette.size(); ++i) colour[ranked[i]->name] = i;
    // The legend: a swatch and the class (percentage) per coloured class, then the rest.
    std::vector<std::pair<std::array<float, 3>, std::string>> legend;
    for (size_t i = 0; i < ranked.size() && i < kPalette.size(); ++i) {
        const std::string name = ranked[i]->length > kMaxBreakdownLength ? fmt::format(">{}", r.max_length) : ranked[i]->name;
        legend.emplace_back(kPalette[i], fmt::format("{} {:.1f}%", name, 100 * ranked[i]->fraction));
    }
    if (ranked.size() > kPalette.size()) {
        double rest = 0;
        for (size_t i = kPalette.size(); i < ranked.size(); ++i) rest += ranked[i]->fraction;
        legend.emplace_back(kOther, fmt::format("other {:.1f}%", 100 * rest));
    }

    const int n_bars = int(lengths.size());
    const int left = 60, top = 20, bottom = 40, plot_h = 300, bar_w = 36, gap = 14;
    const int plot_w = std::max(1, n_bars) * (bar_w + gap) + gap;
    const int legend_x = left + plot_w + 20;
    size_t longest = 0;
    for (const auto& [swatch, text] : legend) longest = std::max(longest, text.size());
    const int legend_w = int(longest) * kAdvance + kTextHeight + 20;
    const int width = legend_x + legend_w;
    const int height = std::max(top + plot_h + bottom, top + int(legend.size()) * (kTextHeight + 6) + 10);
    Canvas img(width, height);
    fill(img, 0, 0, width, height, {1.f, 1.f, 1.f});

    // The y axis runs to the largest length's fraction, rounded up to a multiple of 10%.
    double top_fraction = 0.1;
    for (const auto* l : lengths) top_fraction = std::max(top_fraction, l->fraction);
    top_fraction = std::min(1.0, std::ceil(top_fraction * 10 - 1e-9) / 10);
    auto y_of = [&](double f) { return top + plot_h - int(std::lround(plot_h * std::clamp(f / top_fraction, 0.0, 1.0))); };
    for (int tick = 0; tick * 0.1 <= top_fraction + 1e-9; ++tick) {
        const int y = y_of(tick * 0.1);
        fill(img, left - 4, y, left + plot_w, y + 1, {0.85f, 0.85f, 0.85f});
        draw_text(img, 4, y - kTextHeight / 2, fmt::format("{}%", tick * 10));
    }
    fill(img, left - 1, top, left, top + plot_h + 1, {0.f, 0.f, 0.f});
    fill(img, left - 1, top + plot_h, left + plot_w, top + plot_h + 1, {0.f, 0.f, 0.f});

    for (int b = 0; b < n_bars; ++b) {
        const BreakdownRow& l = *lengths[size_t(b)];
        const int x0 = left + gap + b * (bar_w + gap);
        double below = 0;
        for (const auto* c : classes) {
            if (c->length != l.length || c->fraction <= 0) continue;
            const int y_top = y_of(below + c->fraction), y_bottom = y_of(below);
            auto it = colour.find(c->name);
            fill(img, x0, y_top, x0 + bar_w, y_bottom, it == colour.end() ? kOther : kPalette[it->second]);
            below += c->fraction;
        }
        const std::string label = l.length > kMaxBreakdownLength ? fmt::format(">{}", r.max_length) : fmt::format("{}", l.length);
        draw_text(img, x0 + (bar_w - int(label.size()) * kAdvance) / 2, top + plot_h + 8, label);
    }
    draw_text(img, 4, top + plot_h + 8, "k=");

    int y = top;
    for (const auto& [swatch, text] : legend) {
        fill(img, legend_x, y, legend_x + kTextHeight, y + kTextHeight, swatch);
        draw_text(img, legend_x + kTextHeight + 8, y, text);
        y += kTextHeight + 6;
    }
    if (std::string why = image_library().write_rgb8(path, width, height, img.rgb.data()); !why.empty())
        throw std::runtime_error(path + ": " + why);
}

}  // namespace omega
