#include "render_harness.h"

#include <algorithm>
#include <cmath>
#include <cstring>

namespace omega::test {

namespace {

RenderResult render_with(const SceneDesc& desc, long long spp, uint64_t seed, int threads, int tile_size,
                         const std::optional<BreakdownDesc>& bd) {
    RenderResult r;
    r.scene = Scene::build(desc);
    RenderSettings rs;
    rs.halt.spp = spp;
    rs.seed = seed;
    rs.threads = threads;
    rs.tile_size = tile_size;
    rs.integrator = desc.integrator;
    rs.breakdown = bd;
    r.session = std::make_unique<RenderSession>(*r.scene, rs);
    r.report = r.session->run();
    return r;
}

}  // namespace

RenderResult render(const SceneDesc& desc, long long spp, uint64_t seed, int threads, int tile_size) {
    return render_with(desc, spp, seed, threads, tile_size, std::nullopt);
}

RenderResult render_breakdown(const SceneDesc& desc, long long spp, const BreakdownDesc& bd, uint64_t seed, int threads,
                              int tile_size) {
    return render_with(desc, spp, seed, threads, tile_size, bd);
}

BreakdownReport breakdown(const RenderResult& r) { return r.session->breakdown()->report(); }

const BreakdownRow* breakdown_row(const BreakdownReport& r, const std::string& kind, const std::string& name) {
    for (const auto& row : r.rows)
        if (row.kind == kind && row.name == name) return &row;
    return nullptr;
}

SceneDesc glass_caustic_scene(double lamp_radius, float lamp_radiance) {
    SceneDesc d = empty_scene(24, 24);
    d.integrator.max_depth = 6;
    d.sensor.to_world = Mat4::look_at({-1.3, 2.2, -1.3}, {-1.1, 0, 0}, {0, 1, 0});
    d.sensor.fov = 28;
    d.materials["white"] = diffuse("white", Rgb(0.8f));
    DielectricBsdf glass;
    glass.eta = 1.5f;
    d.materials["glass"] = MaterialDesc{"glass", glass, {}};
    d.materials["black"] = MaterialDesc{"black", BlackBsdf{}, {}};
    ShapeDesc floor;
    floor.type = ShapeType::Rectangle;
    floor.to_world = Mat4::rotate({1, 0, 0}, -90) * Mat4::scale({3, 3, 1});
    floor.material = "white";
    d.shapes.push_back(floor);
    ShapeDesc ball;
    ball.type = ShapeType::Sphere;
    ball.center = {0, 0.6, 0};
    ball.radius = 0.5;
    ball.material = "glass";
    d.shapes.push_back(ball);
    ShapeDesc lamp;
    lamp.type = ShapeType::Sphere;
    lamp.center = {2.0, 2.0, 0};
    lamp.radius = lamp_radius;
    lamp.material = "black";
    lamp.emitter = EmitterDesc{Rgb(lamp_radiance), false};
    d.shapes.push_back(lamp);
    return d;
}

SceneDesc metal_cube_scene(int w, int h) {
    SceneDesc d = empty_scene(w, h);
    d.sensor.to_world = Mat4::look_at({0, 1, -4}, {0, 0.5, 0}, {0, 1, 0});
    d.materials["white"] = diffuse("white", Rgb(0.7f));
    ConductorBsdf rough;
    rough.alpha_u = rough.alpha_v = 0.2f;
    d.materials["metal"] = MaterialDesc{"metal", rough, {}};
    ShapeDesc floor;
    floor.type = ShapeType::Rectangle;
    floor.to_world = Mat4::rotate({1, 0, 0}, -90) * Mat4::scale({3, 3, 1});
    floor.material = "white";
    d.shapes.push_back(floor);
    ShapeDesc cube;
    cube.type = ShapeType::Cube;
    cube.to_world = Mat4::translate({0, 0.5, 0}) * Mat4::rotate({0, 1, 0}, 30) * Mat4::scale({0.5, 0.5, 0.5});
    cube.material = "metal";
    d.shapes.push_back(cube);
    ShapeDesc light;
    light.type = ShapeType::Sphere;
    light.center = {1, 2, -1};
    light.radius = 0.3;
    light.material = "white";
    light.emitter = EmitterDesc{Rgb(10.f), false};
    d.shapes.push_back(light);
    return d;
}

SceneDesc empty_scene(int w, int h) {
    SceneDesc d;
    d.path = "<test>";
    d.sensor.film.width = w;
    d.sensor.film.height = h;
    d.sensor.fov = 60;
    return d;
}

MaterialDesc diffuse(const std::string& name, Rgb reflectance) {
    MaterialDesc m;
    m.name = name;
    m.bsdf = DiffuseBsdf{reflectance, true};
    return m;
}

ZStats z_against(const Film& film, const std::function<double(int, int)>& expected) {
    Rect c = film.crop();
    double diff = 0, var = 0;
    double max_abs = 0;
    for (int y = c.y0; y < c.y1; ++y)
        for (int x = c.x0; x < c.x1; ++x) {
            PixelStats p = film.pixel(x, y);
            double m = (p.mean.x + p.mean.y + p.mean.z) / 3.0;
            // Channels of one sample are correlated: bound the variance of their average by
            // the average of their standard errors, squared (Cauchy-Schwarz).
            double sd = (std::sqrt(p.var_of_mean.x) + std::sqrt(p.var_of_mean.y) + std::sqrt(p.var_of_mean.z)) / 3.0;
            double e = expected(x, y);
            diff += m - e;
            var += sd * sd;
            if (sd > 0) max_abs = std::max(max_abs, std::abs(m - e) / sd);
        }
    ZStats z;
    z.z = var > 0 ? diff / std::sqrt(var) : (diff == 0 ? 0 : INFINITY);
    z.max_abs_z = max_abs;
    z.blocks = int(c.area());
    return z;
}

ZStats z_between(const Film& a, const Film& b, int block) {
    Rect c = a.crop();
    ZStats z;
    double tdiff = 0, tvar = 0;
    for (int by = c.y0; by < c.y1; by += block)
        for (int bx = c.x0; bx < c.x1; bx += block) {
            double diff = 0, var = 0;
            for (int y = by; y < std::min(by + block, c.y1); ++y)
                for (int x = bx; x < std::min(bx + block, c.x1); ++x) {
                    PixelStats pa = a.pixel(x, y), pb = b.pixel(x, y);
                    diff += (pa.mean.x + pa.mean.y + pa.mean.z) / 3.0 - (pb.mean.x + pb.mean.y + pb.mean.z) / 3.0;
                    auto sd = [](const PixelStats& p) {
                        return (std::sqrt(p.var_of_mean.x) + std::sqrt(p.var_of_mean.y) + std::sqrt(p.var_of_mean.z)) / 3.0;
                    };
                    var += sd(pa) * sd(pa) + sd(pb) * sd(pb);
                }
            tdiff += diff;
            tvar += var;
            if (var > 0) z.max_abs_z = std::max(z.max_abs_z, std::abs(diff) / std::sqrt(var));
            else if (diff != 0) z.max_abs_z = INFINITY;
            ++z.blocks;
        }
    z.z = tvar > 0 ? tdiff / std::sqrt(tvar) : 0;
    return z;
}

double z_threshold(int n, double alpha) {
    // Inverse of the two-sided normal tail by bisection on erfc.
    double p = alpha / std::max(1, n);
    double lo = 0, hi = 40;
    for (int i = 0; i < 200; ++i) {
        double mid = 0.5 * (lo + hi);
        if (std::erfc(mid / std::sqrt(2.0)) > p) lo = mid;
        else hi = mid;
    }
    return hi;
}

bool same_bits(const Film& a, const Film& b) {
    const Rect c = a.crop(), d = b.crop();
    if (c.x0 != d.x0 || c.y0 != d.y0 || c.x1 != d.x1 || c.y1 != d.y1) return false;
    for (int y = c.y0; y < c.y1; ++y)
        for (int x = c.x0; x < c.x1; ++x) {
            const PixelState sa = a.state(x, y), sb = b.state(x, y);
            if (sa.n != sb.n || std::memcmp(&sa.w, &sb.w, sizeof sa.w) != 0 ||
                std::memcmp(sa.mean, sb.mean, sizeof sa.mean) != 0 || std::memcmp(sa.m2, sb.m2, sizeof sa.m2) != 0)
                return false;
        }
    return true;
}

}  // namespace omega::test
