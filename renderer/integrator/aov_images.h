#pragma once
// The light path expression outputs of one render: the compiled expressions and one film per
// AOV, filled exactly as the beauty film is.
//  - Path tracing: every camera sample's per-AOV value goes in with Film::add_sample, in the
//    same pixel and sample order as the beauty value (add_sample, from the worker owning the tile).
//  - Light tracing and BDPT: each sample index is one batch, as for the beauty film. The
//    camera-side sums (add_camera, from the worker owning the pixel) and the splats (add_splat,
//    from the ordered splat merge on the driver thread) are summed per AOV in crop-sized
//    buffers and enter the films with add_weighted at the end of the batch (add_batch, driver
//    thread), with the same arithmetic as the beauty's.
// So an AOV's mean and variance are bit-identical for any thread count, and merge, resume and
// partial renders treat them as they treat the beauty.
#include <bit>
#include <vector>

#include "film/aov_film.h"
#include "pathspace/lpe.h"

namespace omega {

class AovImages {
public:
    // Throws std::invalid_argument for a bad name or expression (LpeError names the column).
    AovImages(const FilmDesc& desc, const std::vector<AovDesc>& aovs);

    const LpeSet& lpes() const { return lpes_; }
    size_t size() const { return films_.size(); }
    std::vector<AovFilm>& films() { return films_; }
    const std::vector<AovFilm>& films() const { return films_; }

    // Path tracing: one camera sample's value of each AOV at pixel (x, y).
    template <class Values>
    void add_samples(int x, int y, const Values& values) {
        if (films_.empty()) return;
        const size_t i = films_.front().film.pixel_index(x, y);  // all films share the crop
        for (size_t a = 0; a < films_.size(); ++a) films_[a].film.add_sample_at(i, values.value(a));
    }

    // Splatting integrators. begin_batch() zeroes the buffers (driver thread).
    void begin_batch();
    // `pixel` is the crop-relative row-major index (as the session's batch buffers).
    void add_camera(size_t aov, size_t pixel, const Rgb& v) { camera_[pixel * films_.size() + aov] += Vec3d(v); }
    void add_splat(uint32_t mask, size_t pixel, const Vec3d& v) {
        Vec3d* px = &splats_[pixel * films_.size()];
        for (; mask; mask &= mask - 1) px[size_t(std::countr_zero(mask))] += v;
    }
    // The batch's value at crop pixel `pixel`: camera + splats, the splats times `rescale` when
    // the batch was cut (null: not cut; the beauty adds them unscaled then). Clears the pixel's sums.
    void add_batch(size_t pixel, const double* rescale);
    // After add_batch reached every pixel of the crop: the next begin_batch need not zero.
    void end_batch_complete() { clean_ = true; }

private:
    LpeSet lpes_;
    std::vector<AovFilm> films_;
    // Pixel-major (pixel * AOVs + aov): a splat's AOVs share cache lines, where one crop-sized
    // buffer per AOV cost light tracing a cache miss per AOV per splatted pixel.
    std::vector<Vec3d> camera_, splats_;
    bool clean_ = false;  // the buffers are sized and all zero
};

}  // namespace omega
