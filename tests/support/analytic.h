#pragma once
// Closed forms shared by the analytic scene tests: the point-to-rectangle form factor and the
// box-filtered average of a function over one pixel of a downward-looking orthographic view.
#include <cmath>

namespace omega::test {

// Form factor from a point to the rectangle [0,a] x [0,b] on a parallel plane at height h, the
// point under the corner (0,0). Odd in a and b, so rectangles anywhere follow by inclusion-exclusion.
inline double corner_form_factor(double a, double b, double h) {
    double A = a / h, B = b / h;
    double sa = std::sqrt(1 + A * A), sb = std::sqrt(1 + B * B);
    return (A / sa * std::atan(B / sa) + B / sb * std::atan(A / sb)) / (2 * 3.14159265358979323846);
}

// Form factor from the point (px, py) to the parallel rectangle [x0,x1] x [y0,y1] at height h.
inline double rect_form_factor(double px, double py, double x0, double x1, double y0, double y1, double h) {
    x0 -= px; x1 -= px; y0 -= py; y1 -= py;
    return corner_form_factor(x1, y1, h) - corner_form_factor(x0, y1, h) - corner_form_factor(x1, y0, h) +
           corner_form_factor(x0, y0, h);
}

// Average of f(wx, wy) over pixel (x, y) of a res x res orthographic view of the square centred
// at (cx, cy) with half-size `half`, looking down with +y up (image right is +x): what a box
// filter measures. 4 x 4 Gauss-Legendre points.
template <class F>
double pixel_average(int x, int y, int res, double cx, double cy, double half, F&& f) {
    static const double g[4] = {-0.8611363115940526, -0.3399810435848563, 0.3399810435848563, 0.8611363115940526};
    static const double w[4] = {0.3478548451374538, 0.6521451548625461, 0.6521451548625461, 0.3478548451374538};
    double sum = 0;
    for (int i = 0; i < 4; ++i)
        for (int j = 0; j < 4; ++j) {
            double fx = x + 0.5 + 0.5 * g[i], fy = y + 0.5 + 0.5 * g[j];
            sum += w[i] * w[j] * 0.25 * f(cx + (2 * fx / res - 1) * half, cy + (1 - 2 * fy / res) * half);
        }
    return sum;
}

}  // namespace omega::test
