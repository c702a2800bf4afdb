#pragma once
// Small fixed-size vectors. V3<float> is used for geometry and RGB in the inner loop,
// V3<double> where accumulated error matters (transforms, film sums).
#include <algorithm>
#include <cmath>
#include <cstdint>

namespace omega {

template <class T>
struct V3 {
    T x{}, y{}, z{};
    constexpr V3() = default;
    constexpr V3(T x_, T y_, T z_) : x(x_), y(y_), z(z_) {}
    constexpr explicit V3(T s) : x(s), y(s), z(s) {}
    template <class U>
    constexpr explicit V3(const V3<U>& o) : x(T(o.x)), y(T(o.y)), z(T(o.z)) {}

    constexpr T operator[](int i) const { return i == 0 ? x : (i == 1 ? y : z); }
    constexpr T& operator[](int i) { return i == 0 ? x : (i == 1 ? y : z); }
    constexpr V3 operator-() const { return {-x, -y, -z}; }
    constexpr V3& operator+=(const V3& o) { x += o.x; y += o.y; z += o.z; return *this; }
    constexpr V3& operator-=(const V3& o) { x -= o.x; y -= o.y; z -= o.z; return *this; }
    constexpr V3& operator*=(const V3& o) { x *= o.x; y *= o.y; z *= o.z; return *this; }
    constexpr V3& operator*=(T s) { x *= s; y *= s; z *= s; return *this; }
    constexpr V3& operator/=(T s) { T r = T(1) / s; x *= r; y *= r; z *= r; return *this; }
    constexpr bool operator==(const V3&) const = default;
};

using Vec3 = V3<float>;
using Vec3d = V3<double>;
// RGB radiance, importance or throughput: same storage, component-wise products.
using Rgb = V3<float>;

template <class T> constexpr V3<T> operator+(V3<T> a, const V3<T>& b) { return a += b; }
template <class T> constexpr V3<T> operator-(V3<T> a, const V3<T>& b) { return a -= b; }
template <class T> constexpr V3<T> operator*(V3<T> a, const V3<T>& b) { return a *= b; }
template <class T> constexpr V3<T> operator*(V3<T> a, T s) { return a *= s; }
template <class T> constexpr V3<T> operator*(T s, V3<T> a) { return a *= s; }
template <class T> constexpr V3<T> operator/(V3<T> a, T s) { return a /= s; }
template <class T> constexpr V3<T> operator/(const V3<T>& a, const V3<T>& b) { return {a.x / b.x, a.y / b.y, a.z / b.z}; }

template <class T> constexpr T dot(const V3<T>& a, const V3<T>& b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
template <class T> constexpr T absdot(const V3<T>& a, const V3<T>& b) { return std::abs(dot(a, b)); }
template <class T> constexpr V3<T> cross(const V3<T>& a, const V3<T>& b) {
    return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
template <class T> inline T length_sq(const V3<T>& a) { return dot(a, a); }
template <class T> inline T length(const V3<T>& a) { return std::sqrt(dot(a, a)); }
template <class T> inline V3<T> normalize(const V3<T>& a) { return a / length(a); }
template <class T> inline V3<T> abs(const V3<T>& a) { return {std::abs(a.x), std::abs(a.y), std::abs(a.z)}; }
template <class T> inline V3<T> vmin(const V3<T>& a, const V3<T>& b) { return {std::min(a.x, b.x), std::min(a.y, b.y), std::min(a.z, b.z)}; }
template <class T> inline V3<T> vmax(const V3<T>& a, const V3<T>& b) { return {std::max(a.x, b.x), std::max(a.y, b.y), std::max(a.z, b.z)}; }
template <class T> inline T max_component(const V3<T>& a) { return std::max(a.x, std::max(a.y, a.z)); }
template <class T> inline T min_component(const V3<T>& a) { return std::min(a.x, std::min(a.y, a.z)); }
template <class T> inline T average(const V3<T>& a) { return (a.x + a.y + a.z) / T(3); }
template <class T> inline bool is_black(const V3<T>& a) { return a.x == 0 && a.y == 0 && a.z == 0; }
template <class T> inline bool is_finite(const V3<T>& a) { return std::isfinite(a.x) && std::isfinite(a.y) && std::isfinite(a.z); }
// Flips v into the hemisphere of n.
template <class T> inline V3<T> face_forward(const V3<T>& v, const V3<T>& n) { return dot(v, n) < 0 ? -v : v; }
inline float luminance(const Rgb& c) { return 0.2126f * c.x + 0.7152f * c.y + 0.0722f * c.z; }

struct Vec2 {
    float x{}, y{};
};

constexpr float kPi = 3.14159265358979323846f;
constexpr float kInvPi = 0.31830988618379067154f;
constexpr float kInv2Pi = 0.15915494309189533577f;
constexpr float kInv4Pi = 0.07957747154594766788f;
constexpr double kPiD = 3.14159265358979323846;

inline float safe_sqrt(float x) { return std::sqrt(std::max(0.f, x)); }
inline float sqr(float x) { return x * x; }

}  // namespace omega
