#include "scene/scene_parser.h"

#include "pathspace/lpe.h"
#include "scene/scene_files.h"

#include <fmt/format.h>

#include <climits>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <set>
#include <sstream>

#include "bsdf/metals.h"

namespace omega {

namespace {

namespace fs = std::filesystem;

constexpr double kInf = std::numeric_limits<double>::infinity();

// Range text in interval notation so the message says exactly which ends are allowed.
std::string range_text(double lo, bool lo_open, double hi, bool hi_open) {
    if (hi == kInf) return fmt::format("must be {} {}", lo_open ? ">" : ">=", lo);
    return fmt::format("must be in {}{}, {}{}", lo_open ? "(" : "[", lo, hi, hi_open ? ")" : "]");
}

void check_in(const ParamValue& v, double x, double lo, bool lo_open, double hi, bool hi_open) {
    bool ok = (lo_open ? x > lo : x >= lo) && (hi_open ? x < hi : x <= hi);
    if (!ok) v.fail(fmt::format("{}, got {}", range_text(lo, lo_open, hi, hi_open), x));
}

float float_in(ParamBag& b, const std::string& key, float def, double lo, bool lo_open, double hi, bool hi_open) {
    auto v = b.get(key);
    if (!v) return def;
    float x = v->as_float();
    check_in(*v, x, lo, lo_open, hi, hi_open);
    return x;
}

Rgb rgb_in(ParamBag& b, const std::string& key, Rgb def, double lo, double hi) {
    auto v = b.get(key);
    if (!v) return def;
    Rgb c = v->as_rgb();
    for (int i = 0; i < 3; ++i)
        if (c[i] < lo || c[i] > hi)
            v->fail(fmt::format("components {}, got [{}, {}, {}]", range_text(lo, false, hi, false), c.x, c.y, c.z));
    return c;
}

Rgb required_rgb_nonneg(ParamBag& b, const std::string& key) {
    b.require(key);  // for the "missing key" message; rgb_in reads it again
    return rgb_in(b, key, Rgb{}, 0, kInf);
}

// Keys that belong to another variant get a clearer message than "unknown key".
void reject(ParamBag& b, const std::string& key, const std::string& why) {
    if (auto v = b.get(key)) v->fail("not used " + why);
}

// ---------------------------------------------------------------------------------------------
// Materials

enum class MatType { Diffuse, RoughDiffuse, Conductor, Dielectric, ThinDielectric, Plastic, RoughPlastic, Black };

BitmapDesc parse_bitmap(const ParamValue& v);

// A roughness texture (a mapping) in `alpha` goes to `tex`; au and av then hold a placeholder
// that Scene::build replaces with the texture's mean. alpha_u/alpha_v take numbers only.
void parse_alpha(ParamBag& b, float& au, float& av, std::optional<BitmapDesc>& tex) {
    bool iso = b.has("alpha"), aniso = b.has("alpha_u") || b.has("alpha_v");
    if (iso && aniso) b.get("alpha")->fail("give either alpha or alpha_u/alpha_v, not both");
    if (iso && b.get("alpha")->is_map()) {
        tex = parse_bitmap(*b.get("alpha"));
        au = av = 0.1f;
    } else if (iso) {
        au = av = float_in(b, "alpha", 0.f, 0, false, 1, false);
    } else if (aniso) {
        b.require("alpha_u");
        b.require("alpha_v");
        au = float_in(b, "alpha_u", 0.f, 0, false, 1, false);
        av = float_in(b, "alpha_v", 0.f, 0, false, 1, false);
        if ((au == 0) != (av == 0)) b.get("alpha_v")->fail("alpha_u and alpha_v must both be 0 (smooth) or both > 0");
    }
}

MicrofacetType parse_distribution(ParamBag& b) {
    return b.get_enum<MicrofacetType>("distribution", {{"ggx", MicrofacetType::GGX}, {"beckmann", MicrofacetType::Beckmann}},
                                      MicrofacetType::GGX);
}

// Mitsuba's table of named refractive indices, plus "glass".
std::optional<double> named_ior(const std::string& s) {
    static const std::pair<const char*, double> table[] = {
        {"vacuum", 1.0},           {"helium", 1.000036},        {"hydrogen", 1.000132},
        {"air", 1.000277},         {"carbon dioxide", 1.00045}, {"water", 1.3330},
        {"acetone", 1.36},         {"ethanol", 1.361},          {"carbon tetrachloride", 1.461},
        {"glycerol", 1.4729},      {"benzene", 1.501},          {"silicone oil", 1.52045},
        {"bromine", 1.661},        {"water ice", 1.31},         {"fused quartz", 1.458},
        {"pyrex", 1.470},          {"acrylic glass", 1.49},     {"polypropylene", 1.49},
        {"bk7", 1.5046},           {"glass", 1.5},              {"sodium chloride", 1.544},
        {"amber", 1.55},           {"pet", 1.5750},             {"polystyrene", 1.55},
        {"diamond", 2.419},
    };
    for (auto& [name, v] : table)
        if (s == name) return v;
    return std::nullopt;
}

float parse_ior(ParamBag& b, const std::string& key, float def) {
    auto v = b.get(key);
    if (!v) return def;
    if (v->is_scalar()) {
        if (auto x = named_ior(v->node().Scalar())) return float(*x);
        const std::string& s = v->node().Scalar();
        bool numeric = !s.empty() && (std::isdigit(static_cast<unsigned char>(s[0])) || s[0] == '.' || s[0] == '-' || s[0] == '+');
        if (!numeric)
            v->fail("expected a number or a named IOR (vacuum, air, water, bk7, glass, diamond, ...), got " + v->describe());
    }
    float x = v->as_float();
    check_in(*v, x, 0, true, kInf, false);
    return x;
}

// A file named relative to the scene file's folder: its normalised absolute path, the name as
// written and the value's location. Nothing is opened here: check_scene_files() checks every
// file through the scene's FileGate once the whole scene is parsed.
struct NamedFile {
    std::string file, written;
    SourceLoc loc;
};
NamedFile scene_file(const ParamValue& fv) {
    std::string file = fv.as_string();
    if (file.empty()) fv.fail("must not be empty");
    if (file.find('\0') != std::string::npos) fv.fail("must not contain a NUL byte");
    fs::path p(file);
    if (p.is_relative()) {
        fs::path dir = fs::path(fv.file()).parent_path();
        p = (dir.empty() ? fs::path(".") : dir) / p;
    }
    std::error_code ec;
    fs::path abs = fs::absolute(p, ec);
    return {(ec ? p : abs).lexically_normal().string(), file, fv.loc()};
}

// Two numbers, [a, b], or one number for both when `single_ok`.
std::pair<float, float> pair_of(const ParamValue& v, bool single_ok) {
    if (single_ok && v.is_scalar()) {
        float x = v.as_float();
        return {x, x};
    }
    if (!v.is_list() || v.node().size() != 2)
        v.fail(std::string(single_ok ? "expected a number or [u, v], got " : "expected [u, v], got ") + v.describe());
    auto items = v.as_list();
    return {items[0].as_float(), items[1].as_float()};
}

UvTransform uv_op(const ParamValue& item) {
    ParamBag b(item);
    std::vector<std::pair<std::string, ParamValue>> ops;
    for (const char* op : {"matrix", "translate", "rotate", "scale"})
        if (auto x = b.get(op)) ops.emplace_back(op, *x);
    b.check_unused();
    if (ops.size() != 1)
        item.fail("expected exactly one of matrix, translate, rotate, scale (use a list to combine them)");
    const auto& [op, v] = ops[0];
    UvTransform t;
    if (op == "matrix") {
        if (!v.is_list() || v.node().size() != 6) v.fail("expected 6 numbers [a, b, c, d, e, f] (u' = a u + b v + c, v' = d u + e v + f), got " + v.describe());
        auto items = v.as_list();
        for (size_t i = 0; i < 6; ++i) t.m[i] = items[i].as_float();
    } else if (op == "translate") {
        auto [tu, tv] = pair_of(v, false);
        t.m = {1, 0, tu, 0, 1, tv};
    } else if (op == "scale") {
        auto [su, sv] = pair_of(v, true);
        t.m = {su, 0, 0, 0, sv, 0};
    } else {  // rotate: degrees, counter-clockwise in the (u, v) plane, as Mitsuba's rotation about z
        double a = v.as_double() * kPiD / 180.0;
        float c = float(std::cos(a)), s = float(std::sin(a));
        t.m = {c, -s, 0, s, c, 0};
    }
    return t;
}

UvTransform parse_to_uv(const ParamValue& v) {
    UvTransform t;
    if (v.is_list()) {
        for (const ParamValue& item : v.as_list()) t = uv_op(item).after(t);  // the first applies first
    } else if (v.is_map()) {
        t = uv_op(v);
    } else {
        v.fail("expected a uv transform mapping or a list of them, got " + v.describe());
    }
    for (float x : t.m)
        if (!std::isfinite(x)) v.fail("the uv transform is not finite");
    return t;
}

// A texture mapping: {type: bitmap, file, ...} or {type: checkerboard, color0, color1, to_uv}.
BitmapDesc parse_bitmap(const ParamValue& v) {
    ParamBag b(v);
    BitmapDesc t;
    t.loc = v.loc();
    if (ParamBag::enum_value<int>(b.require("type"), {{"bitmap", 0}, {"checkerboard", 1}}) == 1) {
        t.checker = true;
        t.color0 = rgb_in(b, "color0", t.color0, 0, 1);
        t.color1 = rgb_in(b, "color1", t.color1, 0, 1);
        if (auto u = b.get("to_uv")) t.to_uv = parse_to_uv(*u);
        b.check_unused();
        return t;
    }
    NamedFile f = scene_file(b.require("file"));
    t.file = f.file;
    t.written = f.written;
    t.file_loc = f.loc;
    t.filter = b.get_enum<TexFilter>("filter", {{"bilinear", TexFilter::Bilinear}, {"nearest", TexFilter::Nearest}},
                                     t.filter);
    t.wrap = b.get_enum<TexWrap>("wrap", {{"repeat", TexWrap::Repeat}, {"mirror", TexWrap::Mirror}, {"clamp", TexWrap::Clamp}},
                                 t.wrap);
    t.raw = b.get_bool("raw", t.raw);
    if (auto u = b.get("to_uv")) t.to_uv = parse_to_uv(*u);
    b.check_unused();
    return t;
}

// A colour in [0, 1] that may instead be a texture mapping, which then goes to `tex` (the
// colour keeps `def` until Scene::build puts the texture's mean there).
Rgb rgb_or_texture(ParamBag& b, const char* key, Rgb def, std::optional<BitmapDesc>& tex) {
    if (b.has(key) && b.get(key)->is_map()) {
        tex = parse_bitmap(*b.get(key));
        return def;
    }
    return rgb_in(b, key, def, 0, 1);
}

// Oren-Nayar's alpha (any slope >= 0) or a texture of it.
float roughdiffuse_alpha(ParamBag& b, std::optional<BitmapDesc>& tex) {
    if (b.has("alpha") && b.get("alpha")->is_map()) {
        tex = parse_bitmap(*b.get("alpha"));
        return 0.2f;
    }
    return float_in(b, "alpha", 0.2f, 0, false, kInf, true);
}

MaterialDesc parse_material(const ParamValue& v, const std::string& name, std::vector<std::string>& warnings) {
    ParamBag b(v);
    MaterialDesc m;
    m.name = name;
    m.loc = v.loc();
    MatType type = ParamBag::enum_value<MatType>(b.require("type"), {{"diffuse", MatType::Diffuse},
                                                                     {"roughdiffuse", MatType::RoughDiffuse},
                                                                     {"conductor", MatType::Conductor},
                                                                     {"dielectric", MatType::Dielectric},
                                                                     {"thindielectric", MatType::ThinDielectric},
                                                                     {"plastic", MatType::Plastic},
                                                                     {"roughplastic", MatType::RoughPlastic},
                                                                     {"black", MatType::Black}});
    switch (type) {
        case MatType::Diffuse:
        case MatType::RoughDiffuse: {
            DiffuseBsdf d;
            d.reflectance = rgb_or_texture(b, "reflectance", d.reflectance, m.reflectance_texture);
            d.two_sided = b.get_bool("two_sided", true);
            if (type == MatType::RoughDiffuse) {  // Oren-Nayar, Mitsuba's roughdiffuse
                d.alpha = roughdiffuse_alpha(b, m.alpha_texture);
                d.fast_approx = b.get_bool("fast_approx", false);
            }
            m.bsdf = d;
            break;
        }
        case MatType::Conductor: {
            ConductorBsdf c;
            if (auto mat = b.get("material")) {
                if (b.has("eta") || b.has("k")) mat->fail("give either material or eta/k, not both");
                std::string metal = mat->as_string();
                auto ior = named_metal_ior(metal);
                if (!ior) mat->fail("unknown metal '" + metal + "' (known: Au, Ag, Cu, Al)");
                c.eta = ior->first;
                c.k = ior->second;
                c.has_ior = true;
            } else if (b.has("eta") || b.has("k")) {
                // A lone eta or k would silently pair with a made-up other half.
                b.require("eta");
                b.require("k");
                c.eta = rgb_in(b, "eta", c.eta, 0, kInf);
                c.k = rgb_in(b, "k", c.k, 0, kInf);
                c.has_ior = true;
            }
            c.specular_reflectance = rgb_or_texture(b, "specular_reflectance", c.specular_reflectance, m.specular_texture);
            parse_alpha(b, c.alpha_u, c.alpha_v, m.alpha_texture);
            c.distribution = parse_distribution(b);
            c.two_sided = b.get_bool("two_sided", true);
            m.bsdf = c;
            break;
        }
        case MatType::Dielectric: {
            DielectricBsdf d;
            // Mitsuba's defaults: BK7 glass in air.
            float int_ior = parse_ior(b, "int_ior", 1.5046f);
            float ext_ior = parse_ior(b, "ext_ior", 1.000277f);
            d.eta = int_ior / ext_ior;
            if (d.eta == 1.f)
                warnings.push_back(fmt::format("{}:{}: {}: int_ior equals ext_ior, the interface is invisible",
                                               m.loc.file, m.loc.line, m.loc.key));
            d.specular_reflectance = rgb_or_texture(b, "specular_reflectance", d.specular_reflectance, m.specular_texture);
            d.specular_transmittance =
                rgb_or_texture(b, "specular_transmittance", d.specular_transmittance, m.transmittance_texture);
            parse_alpha(b, d.alpha_u, d.alpha_v, m.alpha_texture);
            d.distribution = parse_distribution(b);
            m.bsdf = d;
            break;
        }
        case MatType::ThinDielectric: {
            ThinDielectricBsdf d;
            // Mitsuba's defaults: BK7 glass in air.
            float int_ior = parse_ior(b, "int_ior", 1.5046f);
            float ext_ior = parse_ior(b, "ext_ior", 1.000277f);
            d.eta = int_ior / ext_ior;
            d.specular_reflectance = rgb_or_texture(b, "specular_reflectance", d.specular_reflectance, m.specular_texture);
            d.specular_transmittance =
                rgb_or_texture(b, "specular_transmittance", d.specular_transmittance, m.transmittance_texture);
            m.bsdf = d;
            break;
        }
        case MatType::Plastic:
        case MatType::RoughPlastic: {
            PlasticBsdf p;
            p.diffuse_reflectance = rgb_or_texture(b, "diffuse_reflectance", p.diffuse_reflectance, m.reflectance_texture);
            p.specular_reflectance = rgb_or_texture(b, "specular_reflectance", p.specular_reflectance, m.specular_texture);
            // Mitsuba's defaults: polypropylene in air.
            float int_ior = parse_ior(b, "int_ior", 1.49f);
            float ext_ior = parse_ior(b, "ext_ior", 1.000277f);
            p.set_eta(int_ior / ext_ior);
            p.nonlinear = b.get_bool("nonlinear", false);
            if (type == MatType::RoughPlastic) {
                // Isotropic only, as Mitsuba's roughplastic and Tungsten's rough_plastic (alpha_u/v
                // are reported as unknown keys). alpha 0 is the smooth coat, as for conductors.
                if (b.has("alpha") && b.get("alpha")->is_map()) {
                    m.alpha_texture = parse_bitmap(*b.get("alpha"));
                    p.alpha = 0.1f;  // Scene::build puts the texture's mean here
                } else {
                    p.alpha = float_in(b, "alpha", 0.1f, 0, false, 1, false);
                }
                p.distribution = parse_distribution(b);
            }
            p.two_sided = b.get_bool("two_sided", true);
            m.bsdf = p;
            break;
        }
        case MatType::Black: m.bsdf = BlackBsdf{}; break;
    }
    // Any material may be masked (Mitsuba's mask wrapper): a number in [0, 1] or a texture whose
    // first channel is the opacity.
    if (b.has("opacity") && b.get("opacity")->is_map())
        m.opacity_texture = parse_bitmap(*b.get("opacity"));
    else
        m.opacity = float_in(b, "opacity", 1.f, 0, false, 1, false);
    // Any material may be bump mapped (Mitsuba's bumpmap wrapper): height = bump_scale x the
    // texture's first channel, in units of uv.
    if (auto v = b.get("bump")) {
        if (!v->is_map()) v->fail("expected a texture mapping ({type: bitmap, ...}), got " + v->describe());
        m.bump_texture = parse_bitmap(*v);
        m.bump_scale = float_in(b, "bump_scale", 1.f, -1e6, false, 1e6, false);
    } else if (b.has("bump_scale")) {
        b.get("bump_scale")->fail("bump_scale needs a bump texture");
    }
    b.check_unused();
    return m;
}

// ---------------------------------------------------------------------------------------------
// Sections

void parse_integrator(ParamBag b, IntegratorDesc& it) {
    it.type = b.get_enum<IntegratorType>(
        "type", {{"path", IntegratorType::Path}, {"light", IntegratorType::Light}, {"bdpt", IntegratorType::Bdpt}},
        it.type);
    if (auto v = b.get("max_depth")) {
        it.max_depth = int(v->as_int(-1, 1 << 20));
        if (it.max_depth == 0) v->fail("must be -1 (unbounded) or >= 1, got 0");
    }
    it.rr_depth = b.get_int("rr_depth", it.rr_depth, 1, 1 << 20);
    b.check_unused();
}

// aov: {NAME: EXPR, ...}: names and expressions are checked here, so a bad one fails at its line.
void parse_aovs(const ParamValue& v, std::vector<AovDesc>& out) {
    if (!v.is_map()) v.fail("expected a mapping {NAME: \"L S+ D E\", ...}, got " + v.describe());
    ParamBag bag = v.as_bag();
    for (const std::string& name : bag.keys()) {
        ParamValue e = *bag.get(name);
        if (!e.is_scalar()) e.fail("expected a light path expression such as \"L S+ D E\", got " + e.describe());
        out.push_back({name, e.as_string()});
        try {
            validate_aov_name(name);
            compile_lpe(out.back().expr);
        } catch (const std::invalid_argument& err) {
            e.fail(err.what());
        }
    }
    if (out.size() > size_t(kMaxAovs)) v.fail("at most " + std::to_string(kMaxAovs) + " aovs per film");
}

void parse_film(ParamBag b, FilmDesc& f) {
    f.width = b.get_int("width", f.width, 1, 1 << 16);
    f.height = b.get_int("height", f.height, 1, 1 << 16);
    f.filter = b.get_enum<FilterType>(
        "filter", {{"box", FilterType::Box}, {"tent", FilterType::Tent}, {"gaussian", FilterType::Gaussian}}, f.filter);
    switch (f.filter) {
        case FilterType::Box: f.filter_radius = 0.5f; break;
        case FilterType::Tent: f.filter_radius = 1.f; break;
        case FilterType::Gaussian:
            f.gaussian_stddev = float_in(b, "stddev", f.gaussian_stddev, 0, true, 16, false);
            f.filter_radius = 4.f * f.gaussian_stddev;  // Mitsuba's cut-off
            break;
    }
    if (f.filter != FilterType::Gaussian) reject(b, "stddev", "by a box or tent filter");
    if (auto v = b.get("crop")) {
        if (!v->is_list() || v->node().size() != 4) v->fail("expected [x0, y0, x1, y1], got " + v->describe());
        auto items = v->as_list();
        for (int i = 0; i < 4; ++i) f.crop[size_t(i)] = int(items[size_t(i)].as_int(0, 1 << 16));
        auto [x0, y0, x1, y1] = f.crop;
        if (!(x0 < x1 && x1 <= f.width && y0 < y1 && y1 <= f.height))
            v->fail(fmt::format("must satisfy 0 <= x0 < x1 <= width ({}) and 0 <= y0 < y1 <= height ({}), got [{}, {}, {}, {}]",
                                f.width, f.height, x0, y0, x1, y1));
        f.has_crop = true;
    } else {
        f.crop = {0, 0, f.width, f.height};
    }
    if (auto v = b.get("aov")) parse_aovs(*v, f.aovs);
    if (auto v = b.get("breakdown")) {
        // breakdown: {length: N, box: [x0, y0, x1, y1]}; the box is checked against the crop by
        // the renderer, which knows it.
        ParamBag bb = v->as_bag();
        FilmDesc::Breakdown bd;
        bd.length = bb.get_int("length", bd.length, 1, 16);
        if (auto bv = bb.get("box")) {
            if (!bv->is_list() || bv->node().size() != 4) bv->fail("expected [x0, y0, x1, y1], got " + bv->describe());
            auto items = bv->as_list();
            std::array<int, 4> box{};
            for (int i = 0; i < 4; ++i) box[size_t(i)] = int(items[size_t(i)].as_int(0, 1 << 16));
            bd.box = box;
        }
        bb.check_unused();
        f.breakdown = bd;
    }
    b.check_unused();
}

void parse_sensor(ParamBag b, SensorDesc& s) {
    s.loc = b.self().loc();
    s.type = b.get_enum<SensorType>("type",
                                    {{"perspective", SensorType::Perspective},
                                     {"thin_lens", SensorType::ThinLens},
                                     {"orthographic", SensorType::Orthographic}},
                                    s.type);
    if (s.type == SensorType::Orthographic) {
        reject(b, "fov", "by an orthographic sensor (its to_world scale sets the extent)");
        reject(b, "fov_axis", "by an orthographic sensor");
    } else {
        s.fov = float_in(b, "fov", s.fov, 0, true, 180, true);
        s.fov_axis = b.get_enum<char>("fov_axis", {{"x", 'x'}, {"y", 'y'}}, s.fov_axis);
    }
    if (s.type == SensorType::ThinLens) {
        s.aperture_radius = float_in(b, "aperture_radius", s.aperture_radius, 0, false, kInf, false);
        s.focus_distance = float_in(b, "focus_distance", s.focus_distance, 0, true, kInf, false);
    } else {
        reject(b, "aperture_radius", "by this sensor type (only thin_lens)");
        reject(b, "focus_distance", "by this sensor type (only thin_lens)");
    }
    if (auto v = b.get("to_world")) s.to_world = parse_to_world(*v);
    s.near_clip = float_in(b, "near_clip", s.near_clip, 0, false, kInf, false);
    s.far_clip = float_in(b, "far_clip", s.far_clip, 0, true, kInf, false);
    if (auto f = b.opt_bag("film")) parse_film(*f, s.film);
    else s.film.crop = {0, 0, s.film.width, s.film.height};
    if (auto v = b.get("spp")) s.halt.spp = v->as_int(1, 1LL << 40);
    if (auto v = b.get("time")) {
        s.halt.time_s = v->as_double();
        check_in(*v, *s.halt.time_s, 0, true, kInf, false);
    }
    if (auto v = b.get("target_error")) {
        s.halt.target_error = v->as_double();
        check_in(*v, *s.halt.target_error, 0, true, kInf, false);
    }
    b.check_unused();
}

EmitterDesc parse_emitter(ParamBag b) {
    EmitterDesc e;
    ParamBag::enum_value<int>(b.require("type"), {{"area", 0}});
    e.radiance = required_rgb_nonneg(b, "radiance");
    e.two_sided = b.get_bool("two_sided", false);
    b.check_unused();
    return e;
}

struct ShapeCtx {
    fs::path dir;
    SceneDesc* desc;
    std::set<std::string>* referenced;
};

ShapeDesc parse_shape(const ParamValue& item, size_t index, ShapeCtx& ctx) {
    ParamBag b(item);
    ShapeDesc s;
    s.loc = item.loc();
    s.type = ParamBag::enum_value<ShapeType>(b.require("type"), {{"mesh", ShapeType::Mesh},
                                                                 {"rectangle", ShapeType::Rectangle},
                                                                 {"cube", ShapeType::Cube},
                                                                 {"sphere", ShapeType::Sphere},
                                                                 {"disk", ShapeType::Disk}});
    s.name = b.get_string("name", "");
    if (auto v = b.get("to_world")) s.to_world = parse_to_world(*v);
    if (s.type == ShapeType::Mesh) {
        NamedFile f = scene_file(b.require("file"));
        s.file = f.file;
        s.written = f.written;
        s.file_loc = f.loc;
        s.face_normals = b.get_bool("face_normals", false);
        s.drop_degenerate = b.get_bool("drop_degenerate", true);
        s.flip_tex_coords = b.get_bool("flip_tex_coords", true);
        if (auto v = b.get("meshes"))
            for (const ParamValue& e : v->as_list()) s.mesh_parts.push_back(int(e.as_int(0, INT_MAX)));
    } else {
        reject(b, "meshes", "by this shape type (only mesh)");
        reject(b, "file", "by this shape type (only mesh)");
        reject(b, "face_normals", "by this shape type (only mesh)");
        reject(b, "drop_degenerate", "by this shape type (only mesh)");
        reject(b, "flip_tex_coords", "by this shape type (only mesh)");
    }
    if (s.type == ShapeType::Sphere) {
        s.center = b.get_vec3("center", s.center);
        if (auto v = b.get("radius")) {
            s.radius = v->as_double();
            check_in(*v, s.radius, 0, true, kInf, false);
        }
    } else {
        reject(b, "center", "by this shape type (only sphere)");
        reject(b, "radius", "by this shape type (only sphere)");
    }
    if (auto v = b.get("material")) {
        if (v->is_map()) {
            std::string name = fmt::format("shapes[{}].material", index);
            while (ctx.desc->materials.count(name)) name += "'";
            ctx.desc->materials[name] = parse_material(*v, name, ctx.desc->warnings);
            s.material = name;
        } else {
            std::string ref = v->as_string();
            auto it = ctx.desc->materials.find(ref);
            // Only named materials can be referenced; inline and default ones have internal names.
            if (it == ctx.desc->materials.end() || it->second.loc.key.rfind("materials.", 0) != 0)
                v->fail("unknown material '" + ref + "'");
            ctx.referenced->insert(ref);
            s.material = ref;
        }
    } else {
        // Mitsuba's default: a grey diffuse surface.
        const std::string name = "(default)";
        if (!ctx.desc->materials.count(name)) ctx.desc->materials[name] = MaterialDesc{name, DiffuseBsdf{}, s.loc};
        s.material = name;
    }
    if (auto e = b.opt_bag("emitter")) s.emitter = parse_emitter(*e);
    s.flip_normals = b.get_bool("flip_normals", false);
    b.check_unused();
    return s;
}

LightDesc parse_light(const ParamValue& item) {
    ParamBag b(item);
    LightDesc l;
    l.loc = item.loc();
    l.type = ParamBag::enum_value<LightType>(b.require("type"), {{"point", LightType::Point},
                                                                 {"spot", LightType::Spot},
                                                                 {"directional", LightType::Directional},
                                                                 {"constant", LightType::Constant},
                                                                 {"envmap", LightType::EnvMap}});
    switch (l.type) {
        case LightType::Point:
            l.position = b.get_vec3("position", l.position);
            l.intensity = required_rgb_nonneg(b, "intensity");
            break;
        case LightType::Spot: {
            if (auto v = b.get("to_world")) l.to_world = parse_to_world(*v);
            l.intensity = required_rgb_nonneg(b, "intensity");
            l.cutoff_angle = float_in(b, "cutoff_angle", 20.f, 0, true, 90, false);
            l.beam_width = 0.75f * l.cutoff_angle;
            if (auto v = b.get("beam_width")) {
                l.beam_width = v->as_float();
                check_in(*v, l.beam_width, 0, true, l.cutoff_angle, false);
            }
            break;
        }
        case LightType::Directional: {
            ParamValue dv = b.require("direction");
            Vec3d d = dv.as_vec3();
            if (!(length(d) > 0) || !std::isfinite(length(d))) dv.fail("must be a non-zero vector");
            l.direction = normalize(d);
            l.irradiance = required_rgb_nonneg(b, "irradiance");
            break;
        }
        case LightType::Constant: l.radiance = required_rgb_nonneg(b, "radiance"); break;
        case LightType::EnvMap: {
            NamedFile f = scene_file(b.require("file"));
            l.file = f.file;
            l.written = f.written;
            l.file_loc = f.loc;
            l.scale = float_in(b, "scale", 1.f, 0, false, kInf, true);
            if (auto v = b.get("to_world")) l.to_world = parse_to_world(*v);
            break;
        }
    }
    b.check_unused();
    return l;
}

SceneDesc parse_root(const YAML::Node& root, const std::string& file, const fs::path& dir) {
    auto fname = std::make_shared<const std::string>(file);
    SceneDesc desc;
    desc.path = file;
    ParamBag top(ParamValue(root, "", fname, 1));

    auto ver = top.get("omega");
    if (!ver) throw SceneError(fmt::format("{}:1: omega: missing key (a v1 scene starts with 'omega: 1')", file));
    long long version = ver->as_int();
    if (version != 1)
        ver->fail(fmt::format("unsupported scene format version {} (this build reads version 1)", version));

    if (auto b = top.opt_bag("integrator")) parse_integrator(*b, desc.integrator);
    if (auto b = top.opt_bag("sampler")) {
        desc.integrator.sampler = b->get_enum<SamplerType>(
            "type", {{"sobol", SamplerType::Sobol}, {"independent", SamplerType::Independent}}, desc.integrator.sampler);
        b->check_unused();
    }
    if (auto b = top.opt_bag("sensor")) parse_sensor(*b, desc.sensor);
    else desc.sensor.film.crop = {0, 0, desc.sensor.film.width, desc.sensor.film.height};

    if (auto mats = top.opt_bag("materials")) {
        for (const std::string& name : mats->keys()) {
            ParamValue v = *mats->get(name);
            if (name.empty()) v.fail("material names must not be empty");
            desc.materials[name] = parse_material(v, name, desc.warnings);
        }
    }

    std::set<std::string> referenced;
    ShapeCtx ctx{dir, &desc, &referenced};
    std::vector<ParamValue> shapes = top.list("shapes");
    for (size_t i = 0; i < shapes.size(); ++i) desc.shapes.push_back(parse_shape(shapes[i], i, ctx));
    for (const ParamValue& v : top.list("lights")) desc.lights.push_back(parse_light(v));
    top.check_unused();

    for (auto& [name, m] : desc.materials)
        if (m.loc.key.rfind("materials.", 0) == 0 && !referenced.count(name))
            desc.warnings.push_back(fmt::format("{}:{}: {}: never used by any shape", m.loc.file, m.loc.line, m.loc.key));
    bool any_light = !desc.lights.empty();
    for (const ShapeDesc& s : desc.shapes) any_light |= s.emitter.has_value() && !is_black(s.emitter->radiance);
    if (!any_light) desc.warnings.push_back(fmt::format("{}:1: the scene has no light source; the image will be black", file));
    return desc;
}

}  // namespace

IntegratorDesc parse_integrator_value(const ParamValue& v) {
    IntegratorDesc it;
    parse_integrator(ParamBag(v), it);
    return it;
}

SensorDesc parse_sensor_value(const ParamValue& v) {
    SensorDesc s;
    parse_sensor(ParamBag(v), s);
    return s;
}

MaterialDesc parse_material_value(const ParamValue& v, const std::string& name, std::vector<std::string>& warnings) {
    return parse_material(v, name, warnings);
}

EmitterDesc parse_emitter_value(const ParamValue& v) { return parse_emitter(ParamBag(v)); }

LightDesc parse_light_value(const ParamValue& v) { return parse_light(v); }

SceneDesc parse_scene_string(const std::string& yaml, const std::string& virtual_path,
                             std::shared_ptr<const FileGate> files) {
    YAML::Node root;
    try {
        root = YAML::Load(yaml);
    } catch (const YAML::Exception& e) {
        throw SceneError(fmt::format("{}:{}: invalid YAML: {}", virtual_path, std::max(e.mark.line + 1, 1), e.msg));
    }
    fs::path dir = fs::path(virtual_path).parent_path();
    if (dir.empty()) dir = ".";
    try {
        SceneDesc desc = parse_root(root, virtual_path, dir);
        desc.files = std::move(files);
        check_scene_files(desc);
        return desc;
    } catch (const YAML::Exception& e) {
        // Should not happen (the bag checks node kinds first), but a library quirk must not escape
        // as anything other than a scene error.
        throw SceneError(fmt::format("{}:{}: invalid YAML: {}", virtual_path, std::max(e.mark.line + 1, 1), e.msg));
    }
}

SceneDesc parse_scene_file(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    std::error_code ec;
    if (!in || fs::is_directory(path, ec)) throw SceneError(fmt::format("{}: cannot open the scene file", path));
    std::stringstream ss;
    ss << in.rdbuf();
    return parse_scene_string(ss.str(), path);
}

}  // namespace omega
