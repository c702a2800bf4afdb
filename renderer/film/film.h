#pragma once
// The film: per-pixel running mean and variance in double precision.
//
// Filtering is done by filter importance sampling (the sample position is drawn from the
// filter), so every sample lands in exactly one pixel with weight 1. A pixel's statistics are
// then a plain sample mean, and its variance-of-the-mean estimate is valid.
//
// Concurrency: add_sample() on pixel p may be called by one thread at a time; the renderer
// guarantees it by giving each tile to one worker. Reads (pixel(), write) happen between passes.
#include <array>
#include <map>
#include <cstdint>
#include <string>
#include <vector>

#include "math/vec.h"
#include "scene/scene_desc.h"

namespace omega {

struct Rect {
    int x0 = 0, y0 = 0, x1 = 0, y1 = 0;  // [x0, x1) x [y0, y1)
    int width() const { return x1 - x0; }
    int height() const { return y1 - y0; }
    long long area() const { return (long long)width() * height(); }
};

struct PixelStats {
    Vec3d mean;
    Vec3d var_of_mean;  // estimated variance of the mean: M2 / (n (n - 1)); 0 for n < 2
    uint64_t n = 0;
};

struct ErrorEstimate {
    double mean_rel_error = 0;     // mean over pixels of sqrt(var)/max(mean, eps), luminance-free (channel average)
    double image_mean = 0;         // mean of all pixel means (channel average)
    double image_mean_stderr = 0;  // standard error of image_mean
};

class Film {
public:
    explicit Film(const FilmDesc& desc);

    int width() const;   // full film
    int height() const;
    Rect crop() const;   // region actually rendered (the whole film without a crop)
    // Tiles covering crop(), in a fixed order.
    std::vector<Rect> tiles(int tile_size) const;

    // Continuous film position (pixels, origin top-left) of a sample for pixel (x, y),
    // drawn from the filter centred on the pixel centre.
    Vec2 sample_position(int x, int y, Vec2 u) const;

    void add_sample(int x, int y, const Rgb& value);
    PixelStats pixel(int x, int y) const;
    ErrorEstimate estimate_error(double eps = 1e-2) const;
    void clear();

private:
    struct Accum {
        double mean[3];
        double m2[3];
        uint64_t n;
    };
    FilmDesc desc_;
    Rect crop_;
    std::vector<Accum> px_;  // crop-sized, row-major
};

// Header attributes DESIGN.md names (omega.*).
struct ExrMeta {
    long long spp = 0;
    double time_s = 0;
    std::string integrator;
    uint64_t seed = 0;
    uint64_t nonfinite = 0;
    std::vector<std::string> warnings;
    double rel_error = 0;  // omega.rel_error: estimated relative error at the end
};

// Writes R,G,B and var.R,var.G,var.B (float32). The data window is the crop, the display window
// the full film. Throws std::runtime_error on I/O failure (message names the path).
void write_exr(const std::string& path, const Film& film, const ExrMeta& meta);

// Reads an RGB EXR (any channels R,G,B; var.* if present) for tests and comparisons.
struct ExrImage {
    int width = 0, height = 0;  // data window size
    std::vector<float> rgb;     // 3 per pixel
    std::vector<float> var;     // 3 per pixel, empty if absent
    std::map<std::string, std::string> attributes;  // omega.* attributes rendered as text
};
ExrImage read_exr(const std::string& path);

}  // namespace omega
