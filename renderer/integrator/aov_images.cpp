#include "integrator/aov_images.h"

namespace omega {

AovImages::AovImages(const FilmDesc& desc, const std::vector<AovDesc>& aovs) : lpes_(aovs) {
    for (const AovDesc& a : aovs) films_.push_back({a.name, a.expr, Film(desc)});
}

void AovImages::begin_batch() {
    // A batch that reached every pixel left the buffers zero (add_batch clears what it adds), so
    // they are zeroed here only after a cut or aborted batch: one pass over them per batch.
    if (clean_) {
        clean_ = false;
        return;
    }
    const size_t n = films_.empty() ? 0 : size_t(films_.front().film.crop().area()) * films_.size();
    camera_.assign(n, Vec3d(0.0));
    splats_.assign(n, Vec3d(0.0));
}

void AovImages::add_batch(size_t pixel, const double* rescale) {
    const size_t n = films_.size(), base = pixel * n;
    for (size_t a = 0; a < n; ++a) {
        Vec3d& c = camera_[base + a];
        Vec3d& sp = splats_[base + a];
        films_[a].film.add_weighted_at(pixel, rescale ? c + sp * *rescale : c + sp, 1.0);
        c = sp = Vec3d(0.0);
    }
}

}  // namespace omega
