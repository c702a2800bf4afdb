#pragma once
// Internal to sensor/: the mapping between the local image plane and film positions, shared by
// the t = 1 connection (sensor_importance.cpp) and the lens hits of t = 0 (sensor_lens.cpp).
#include "sensor/sensor.h"

namespace omega::film_plane {

// Local image-plane point (extent ex, ey; +x is the image's left) -> film position in pixels.
inline Vec2 to_film(float qx, float qy, float ex, float ey, int w, int h) {
    return {(1.f - qx / ex) * float(w) * 0.5f, (1.f - qy / ey) * float(h) * 0.5f};
}

// Film positions whose filter footprint reaches a crop pixel.
inline bool near_crop(const Rect2i& c, Vec2 p, float r) {
    return p.x > float(c.x0) - r && p.x < float(c.x1) + r && p.y > float(c.y0) - r && p.y < float(c.y1) + r;
}

}  // namespace omega::film_plane
