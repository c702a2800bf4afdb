#pragma once
// The film: per-pixel running mean and variance in double precision.
//
// Filtering is done by filter importance sampling (the sample position is drawn from the
// filter), so every sample lands in exactly one pixel with weight 1. A pixel's statistics are
// then a plain sample mean, and its variance-of-the-mean estimate is valid.
//
// Concurrency: add_sample() on pixel p may be called by one thread at a time; the renderer
// guarantees it by giving each tile to one worker. Different pixels may be written concurrently
// from different threads: each pixel's accumulator has a cache line of its own, so workers on
// neighbouring tiles do not false-share. sample_position(), tiles() and the size queries read
// no pixel data and are safe from any thread at any time. Everything that reads or resets pixels
// (pixel(), estimate_error(), merge(), serialize(), clear(), write_exr, encode_exr_tile) must not
// overlap any add_sample(): call them between passes. pixel() and encode_exr_tile() read only
// the pixels they are given, so they may run on a tile no thread is writing while others render
// (the daemon streams a tile as soon as it is done).
#include <array>
#include <map>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "film/filter.h"
#include "film/zeroed_array.h"
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

// A pixel's exact accumulator state: what a partial render carries so that parts merge as
// Film::merge would (film/partial_exr.h).
struct PixelState {
    uint64_t n = 0;  // samples (or batches) added
    double w = 0;    // sum of their weights
    double mean[3] = {0, 0, 0};
    double m2[3] = {0, 0, 0};
};

struct ErrorEstimate {
    double mean_rel_error = 0;     // mean over pixels of sqrt(var)/max(mean, eps), luminance-free (channel average)
    double image_mean = 0;         // mean of all pixel means (channel average)
    double image_mean_stderr = 0;  // standard error of image_mean
};

class Film {
public:
    // Throws std::invalid_argument for a non-positive size, an empty or out-of-bounds crop, or
    // bad filter parameters.
    explicit Film(const FilmDesc& desc);

    const FilmDesc& desc() const { return desc_; }
    const Filter& filter() const { return filter_; }

    int width() const;   // full film
    int height() const;
    Rect crop() const;   // region actually rendered (the whole film without a crop)
    // Tiles covering crop() exactly once, row-major (top row first, left to right); edge tiles
    // are clipped to the crop. Throws std::invalid_argument for tile_size <= 0.
    std::vector<Rect> tiles(int tile_size) const;

    // Continuous film position (pixels, origin top-left) of a sample for pixel (x, y),
    // drawn from the filter centred on the pixel centre.
    Vec2 sample_position(int x, int y, Vec2 u) const;

    // (x, y) is the pixel the sample was drawn for (full-film coordinates, inside crop()), not
    // where sample_position() put it; outside the crop throws std::out_of_range (as does
    // pixel()). The caller drops non-finite values (and counts them): one would poison the pixel.
    void add_sample(int x, int y, const Rgb& value);
    // One batch mean (e.g. one sample index of a splatting integrator) standing for `weight` samples.
    // Variance then comes from the spread of batch means: valid where per-sample statistics
    // are not (light-tracing splats land in pixels without a per-pixel sample count).
    void add_weighted(int x, int y, const Vec3d& value, double weight);
    // The same updates for pixel i of the crop (row-major, as pixel_index gives it), unchecked:
    // for callers that add to several films at one pixel (AOVs) and checked it once.
    size_t pixel_index(int x, int y) const { return index(x, y); }
    void add_sample_at(size_t i, const Rgb& value) { add_weighted_at(i, Vec3d(value), 1.0); }
    // Inline: the splatting integrators' batch loop calls it per pixel for the beauty and every AOV.
    void add_weighted_at(size_t i, const Vec3d& value, double weight) {
        Accum& a = px_[i];
        // Weighted Welford (West 1979): stable where sum/sum-of-squares cancels catastrophically
        // (bright, low-variance pixels). With unit weights it is the classic update.
        a.n += 1;
        a.w += weight;
        const double f = weight / a.w;
        for (int c = 0; c < 3; ++c) {
            const double v = value[c];
            const double delta = v - a.mean[c];
            a.mean[c] += delta * f;
            a.m2[c] += weight * delta * (v - a.mean[c]);
        }
    }
    PixelStats pixel(int x, int y) const;
    // Pixels with fewer than 2 samples have no variance estimate; while any exists in the crop,
    // mean_rel_error and image_mean_stderr are +inf so that a target-error halt cannot fire.
    ErrorEstimate estimate_error(double eps = 1e-2) const;
    // The same estimate in two steps, so that a caller with workers can share out the first:
    // error_part(c) sums chunk c (kErrorChunk pixels in row-major order; 16 chunks at 256x256,
    // enough for 16 workers) and error_of() adds the chunks' sums in chunk order, so the bits
    // are the same however the chunks ran (estimate_error() is both steps on one thread). On
    // one thread a 1024x1024 film took about 25 ms, once a pass, while every other worker waited.
    // Concurrency: error_part() is const and reads only its chunk; call it while nothing adds
    // to the film.
    struct ErrorPart {
        double rel = 0, mean = 0, var = 0;
        bool unknown = false;  // a pixel with fewer than 2 samples
    };
    static constexpr size_t kErrorChunk = 4096;
    size_t error_parts() const { return (px_.size() + kErrorChunk - 1) / kErrorChunk; }
    ErrorPart error_part(size_t chunk, double eps = 1e-2) const;
    ErrorEstimate error_of(std::span<const ErrorPart> parts) const;
    void clear();

    PixelState state(int x, int y) const;
    // Throws std::runtime_error for a state no film could hold (non-finite or negative
    // statistics, a weight without samples); std::out_of_range outside the crop.
    void set_state(int x, int y, const PixelState& s);

    // Adds other's samples to this film, as if they had been added here (Chan et al.'s pairwise
    // update of mean and M2). Throws std::invalid_argument unless size and crop are equal.
    void merge(const Film& other);

    // Compact little-endian snapshot of the statistics (not the filter), for checkpoints.
    std::vector<uint8_t> serialize() const;
    // Throws std::runtime_error if the bytes are corrupt or truncated, or were written for a
    // film of another size or crop than desc's.
    static Film deserialize(const FilmDesc& desc, std::span<const uint8_t> bytes);

private:
    // One cache line per pixel: workers on adjacent tiles never write the same line.
    struct alignas(64) Accum {
        double mean[3];
        double m2[3];
        uint64_t n;  // samples (or batches) added
        double w;    // sum of their weights (= n for unit weights)
    };
    static_assert(sizeof(Accum) == 64);
    size_t index(int x, int y) const;

    FilmDesc desc_;
    Filter filter_;
    Rect crop_;
    ZeroedArray<Accum> px_;  // crop-sized, row-major; pages fault in as tiles first touch them
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
    // Extra RGB layers written as NAME.R, NAME.G, NAME.B (debug output such as per-strategy
    // images); each is crop-sized, row-major, 3 floats per pixel.
    struct Layer {
        std::string name;
        std::vector<float> rgb;
    };
    std::vector<Layer> layers;
    // Extra string attributes (e.g. a partial render's omega.samples).
    std::map<std::string, std::string> attributes;
    // Extra UINT channels, one uint32 per pixel each, crop-sized and row-major: exact data that
    // floats cannot carry (a partial render's accumulator state).
    struct UintChannel {
        std::string name;
        std::vector<uint32_t> data;
    };
    std::vector<UintChannel> uint_channels;
    // ZIP by default. Streamed tiles are written uncompressed: on a noisy 32x32 float tile ZIP
    // took 0.45 ms and made it larger (25.2 KB against 24.6 KB raw), and tiles of a pass are
    // encoded only while someone watches, so it was most of what a watcher cost the daemon.
    bool compress = true;
};

// Writes R,G,B and var.R,var.G,var.B (float32). The data window is the crop, the display window
// the full film. Throws std::runtime_error on I/O failure (message names the path).
// ZIP-compressed. Written to PATH.tmp, flushed to disk and renamed over PATH, so a reader sees
// the old file or the new one, never a partial one.
void write_exr(const std::string& path, const Film& film, const ExrMeta& meta);

// Threads OpenEXR may use to compress (and decompress) blocks of one file; process-wide. Call it
// once at start-up: a 1024² image compresses in about a third of a second on one thread.
void set_exr_threads(int threads);

// Reads an RGB EXR (any channels R,G,B; var.* if present) for tests and comparisons.
struct ExrImage {
    int width = 0, height = 0;  // data window size
    int x0 = 0, y0 = 0;         // data window origin (within the display window)
    int display_width = 0, display_height = 0;
    std::vector<float> rgb;     // 3 per pixel
    std::vector<float> var;     // 3 per pixel, empty if absent
    // Every string, int, float and double attribute (omega.* and standard ones) as text;
    // floating-point values in shortest round-trip form.
    std::map<std::string, std::string> attributes;
    // Every UINT channel by name (the image's size, row-major); empty for most files.
    std::map<std::string, std::vector<uint32_t>> uint_channels;
};
// Throws std::runtime_error naming the path on failure, a missing R/G/B channel, or a data
// window larger than max_pixels.
ExrImage read_exr(const std::string& path, long long max_pixels = 1LL << 26);

// One extra RGB layer of a file (LAYER.R, LAYER.G, LAYER.B, float, e.g. "aov.caustics"), 3 floats
// per pixel of the data window, row-major. Throws std::runtime_error naming the path and the
// missing channel.
std::vector<float> read_exr_layer(const std::string& path, const std::string& layer);

// In-memory EXR of one rectangle of the film (inside crop()), same channels and attributes as
// write_exr; the data window is rect, the display window the full film. For progressive tiles.
std::vector<uint8_t> encode_exr_tile(const Film& film, const Rect& rect, const ExrMeta& meta);
// The same file format for an image already in memory (R,G,B and var.*, the latter zero if absent),
// with the given attributes; e.g. a client that assembled streamed tiles. Throws
// std::invalid_argument when the buffers do not match the size or the data window lies outside
// the display window.
std::vector<uint8_t> encode_exr_image(const ExrImage& img, const ExrMeta& meta);
// Writes bytes to PATH.tmp, fsyncs and renames it over PATH (what write_exr does). Throws
// std::runtime_error naming the path on failure.
void write_file_atomic(const std::string& path, std::span<const uint8_t> bytes);

// Decodes bytes from the network or a cache: anything malformed or truncated, or a data window
// over max_pixels, throws std::runtime_error.
ExrImage decode_exr_memory(std::span<const uint8_t> bytes, long long max_pixels = 1LL << 24);

}  // namespace omega
