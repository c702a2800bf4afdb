#pragma once
// A light path expression output (AOV) as it is stored and exchanged: its name, its expression
// and a Film of its own (mean and variance per pixel, exactly like the beauty image).
#include <string>
#include <vector>

#include "film/film.h"

namespace omega {

struct AovFilm {
    std::string name;
    std::string expr;
    Film film;
};

// Appends the EXR layers of each AOV: "aov.NAME" (the mean) and "aov.NAME.var" (the variance of
// the mean), written as aov.NAME.R/G/B and aov.NAME.var.R/G/B. Any thread, with no add running.
void append_aov_layers(const std::vector<AovFilm>& aovs, ExrMeta& meta);
// The same layers for one rectangle of the films (the daemon's progressive tiles).
void append_aov_tile_layers(const std::vector<AovFilm>& aovs, const Rect& rect, ExrMeta& meta);

// "NAME=EXPR" lines (the omega.aovs attribute of a part), and back. Names are identifiers and
// expressions hold neither '=' nor a newline, so the text is unambiguous.
std::string format_aov_list(const std::vector<AovFilm>& aovs);
std::vector<std::pair<std::string, std::string>> parse_aov_list(const std::string& text);

}  // namespace omega
