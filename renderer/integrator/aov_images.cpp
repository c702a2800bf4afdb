#include "integrator/aov_images.h"

namespace omega {

AovImages::AovImages(const FilmDesc& desc, const std::vector<AovDesc>& aovs) : lpes_(aovs) {
    for (const AovDesc& a : aovs) films_.push_back({a.name, a.expr, Film(desc)});
}

void AovImages::begin_batch() {
    const size_t n = films_.empty() ? 0 : size_t(films_.front().film.crop().area());
    camera_.resize(films_.size());
    splats_.resize(films_.size());
    for (size_t a = 0; a < films_.size(); ++a) {
        camera_[a].assign(n, Vec3d(0.0));
        splats_[a].assign(n, Vec3d(0.0));
    }
}

void AovImages::add_batch(size_t pixel, const double* rescale) {
    for (size_t a = 0; a < films_.size(); ++a) {
        const Vec3d v = rescale ? camera_[a][pixel] + splats_[a][pixel] * *rescale : camera_[a][pixel] + splats_[a][pixel];
        films_[a].film.add_weighted_at(pixel, v, 1.0);
    }
}

}  // namespace omega
