#pragma once
// Test helper shared by film_test.cpp and exr_io_test.cpp.
#include "film/film.h"

namespace omega::test {

// A w x h film whose crop window is [x0, x1) x [y0, y1).
inline FilmDesc cropped(int w, int h, int x0, int y0, int x1, int y1) {
    FilmDesc d;
    d.width = w;
    d.height = h;
    d.has_crop = true;
    d.crop = {x0, y0, x1, y1};
    return d;
}

}  // namespace omega::test
