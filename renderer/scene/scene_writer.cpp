#include "scene/scene_writer.h"

#include <fmt/format.h>

#include <unistd.h>

#include <charconv>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <stdexcept>

namespace omega {

namespace {

namespace fs = std::filesystem;

// Shortest text that reads back (as the parser reads it: double, then float) to exactly f.
std::string num(float f) {
    std::string s = fmt::format("{}", f);
    double d = 0;
    std::from_chars(s.data(), s.data() + s.size(), d);
    if (float(d) != f) s = fmt::format("{}", double(f));  // exact: every float is a double
    return s;
}
std::string num(double d) { return fmt::format("{}", d); }  // shortest round-trip form

std::string rgb(const Rgb& c) { return fmt::format("[{}, {}, {}]", num(c.x), num(c.y), num(c.z)); }
std::string vec(const Vec3d& v) { return fmt::format("[{}, {}, {}]", num(v.x), num(v.y), num(v.z)); }
std::string matrix(const Mat4& m) {
    std::string s = "{matrix: [";
    for (size_t i = 0; i < 16; ++i) s += (i ? ", " : "") + num(m.m[i]);
    return s + "]}";
}
bool is_identity(const Mat4& m) { return m.m == Mat4{}.m; }

// A YAML double-quoted string.
std::string q(const std::string& s) {
    std::string out = "\"";
    for (unsigned char c : s) {
        if (c == '"') out += "\\\"";
        else if (c == '\\') out += "\\\\";
        else if (c < 0x20 || c == 0x7f) out += fmt::format("\\x{:02x}", c);
        else out += char(c);
    }
    return out + "\"";
}

const char* dist(MicrofacetType t) { return t == MicrofacetType::Beckmann ? "beckmann" : "ggx"; }

std::string alpha(float au, float av) {
    if (au == av) return fmt::format(", alpha: {}", num(au));
    return fmt::format(", alpha_u: {}, alpha_v: {}", num(au), num(av));
}

// Where files are written relative to, and the names the embedded images take.
struct Names {
    std::string base_dir;
    std::map<const EmbeddedImage*, std::string> embedded;
};

// A path relative to base_dir when it is given and the path can be expressed so.
std::string rel_path(const std::string& file, const std::string& base_dir) {
    if (base_dir.empty()) return file;
    std::error_code ec;
    fs::path rel = fs::relative(fs::path(file), fs::absolute(fs::path(base_dir), ec), ec);
    return !ec && !rel.empty() ? rel.generic_string() : file;
}

std::string bitmap(const BitmapDesc& t, const Names& names) {
    if (t.checker) {
        std::string s = fmt::format("{{type: checkerboard, color0: {}, color1: {}", rgb(t.color0), rgb(t.color1));
        if (!t.to_uv.is_identity()) {
            s += ", to_uv: {matrix: [";
            for (size_t i = 0; i < 6; ++i) s += (i ? ", " : "") + num(t.to_uv.m[i]);
            s += "]}";
        }
        return s + "}";
    }
    const std::string file = t.embedded ? names.embedded.at(t.embedded.get()) : rel_path(t.file, names.base_dir);
    std::string s = fmt::format("{{type: bitmap, file: {}, filter: {}, wrap: {}, raw: {}", q(file),
                                t.filter == TexFilter::Nearest ? "nearest" : "bilinear",
                                t.wrap == TexWrap::Clamp ? "clamp" : t.wrap == TexWrap::Mirror ? "mirror" : "repeat", t.raw);
    if (!t.to_uv.is_identity()) {
        s += ", to_uv: {matrix: [";
        for (size_t i = 0; i < 6; ++i) s += (i ? ", " : "") + num(t.to_uv.m[i]);
        s += "]}";
    }
    return s + "}";
}

std::string material_bsdf(const MaterialDesc& m, const Names& names) {
    const Bsdf& b = m.bsdf;
    // A parameter as its texture where it has one, else as its value.
    auto tex_or = [&](const std::optional<BitmapDesc>& t, const std::string& value) {
        return t ? bitmap(*t, names) : value;
    };
    auto alpha_of = [&](float au, float av) {
        return m.alpha_texture ? ", alpha: " + bitmap(*m.alpha_texture, names) : alpha(au, av);
    };
    if (auto* d = std::get_if<DiffuseBsdf>(&b)) {
        const std::string refl = tex_or(m.reflectance_texture, rgb(d->reflectance));
        if (d->alpha > 0)
            return fmt::format("{{type: roughdiffuse, reflectance: {}, alpha: {}, fast_approx: {}, two_sided: {}}}", refl,
                               tex_or(m.alpha_texture, num(d->alpha)), d->fast_approx, d->two_sided);
        return fmt::format("{{type: diffuse, reflectance: {}, two_sided: {}}}", refl, d->two_sided);
    }
    if (auto* c = std::get_if<ConductorBsdf>(&b)) {
        std::string s = "{type: conductor";
        if (c->has_ior) s += fmt::format(", eta: {}, k: {}", rgb(c->eta), rgb(c->k));
        s += ", specular_reflectance: " + tex_or(m.specular_texture, rgb(c->specular_reflectance));
        s += alpha_of(c->alpha_u, c->alpha_v);
        return s + fmt::format(", distribution: {}, two_sided: {}}}", dist(c->distribution), c->two_sided);
    }
    if (auto* d = std::get_if<DielectricBsdf>(&b)) {
        // int_ior / ext_ior reproduces eta exactly with ext_ior 1.
        return fmt::format(
            "{{type: dielectric, int_ior: {}, ext_ior: 1, specular_reflectance: {}, specular_transmittance: {}{}, "
            "distribution: {}}}",
            num(d->eta), tex_or(m.specular_texture, rgb(d->specular_reflectance)),
            tex_or(m.transmittance_texture, rgb(d->specular_transmittance)), alpha_of(d->alpha_u, d->alpha_v),
            dist(d->distribution));
    }
    if (auto* d = std::get_if<ThinDielectricBsdf>(&b))
        return fmt::format("{{type: thindielectric, int_ior: {}, ext_ior: 1, specular_reflectance: {}, "
                           "specular_transmittance: {}}}",
                           num(d->eta), tex_or(m.specular_texture, rgb(d->specular_reflectance)),
                           tex_or(m.transmittance_texture, rgb(d->specular_transmittance)));
    if (auto* p = std::get_if<PlasticBsdf>(&b)) {
        // int_ior / ext_ior reproduces eta exactly with ext_ior 1 (and with it fdr_int).
        std::string s = fmt::format("{{type: {}, diffuse_reflectance: {}, specular_reflectance: {}, int_ior: {}, ext_ior: 1, "
                                    "nonlinear: {}",
                                    p->alpha == 0 ? "plastic" : "roughplastic",
                                    tex_or(m.reflectance_texture, rgb(p->diffuse_reflectance)),
                                    tex_or(m.specular_texture, rgb(p->specular_reflectance)), num(p->eta), p->nonlinear);
        if (p->alpha != 0)
            s += fmt::format(", alpha: {}, distribution: {}", tex_or(m.alpha_texture, num(p->alpha)), dist(p->distribution));
        return s + fmt::format(", two_sided: {}}}", p->two_sided);
    }
    return "{type: black}";
}

std::string material(const MaterialDesc& m, const Names& names) {
    std::string s = material_bsdf(m, names);
    if (m.opacity_texture || m.opacity != 1.f) {
        s.pop_back();  // the closing brace
        s += ", opacity: " + (m.opacity_texture ? bitmap(*m.opacity_texture, names) : num(m.opacity)) + "}";
    }
    if (m.bump_texture) {
        s.pop_back();
        s += ", bump: " + bitmap(*m.bump_texture, names) + ", bump_scale: " + num(m.bump_scale) + "}";
    }
    return s;
}

const char* shape_type(ShapeType t) {
    switch (t) {
        case ShapeType::Mesh: return "mesh";
        case ShapeType::Rectangle: return "rectangle";
        case ShapeType::Cube: return "cube";
        case ShapeType::Sphere: return "sphere";
        case ShapeType::Disk: return "disk";
    }
    return "?";
}

const char* filter_name(FilterType f) {
    switch (f) {
        case FilterType::Box: return "box";
        case FilterType::Tent: return "tent";
        case FilterType::Gaussian: return "gaussian";
    }
    return "?";
}

// The textures of every material, in the order the writer writes them.
template <class F>
void for_each_texture(const SceneDesc& d, F&& f) {
    for (const auto& [name, m] : d.materials)
        for (const auto* t : m.texture_slots())
            if (*t) f(**t);
}

// `name` with "_N" before its extension.
std::string numbered(const std::string& name, int n) {
    const size_t dot = name.rfind('.');
    if (dot == std::string::npos || dot == 0) return fmt::format("{}_{}", name, n);
    return fmt::format("{}_{}{}", name.substr(0, dot), n, name.substr(dot));
}

// Writes `bytes` to `path` whole or not at all: a temporary beside it, then a rename.
void write_file_atomically(const fs::path& path, const std::string& bytes) {
    const fs::path tmp = path.parent_path() / fmt::format(".{}.tmp-{}", path.filename().string(), ::getpid());
    {
        std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
        out.write(bytes.data(), std::streamsize(bytes.size()));
        out.flush();
        if (!out) {
            std::error_code ec;
            fs::remove(tmp, ec);
            throw std::runtime_error("cannot write '" + path.string() + "'");
        }
    }
    std::error_code ec;
    fs::rename(tmp, path, ec);
    if (ec) {
        fs::remove(tmp, ec);
        throw std::runtime_error("cannot write '" + path.string() + "'");
    }
}

}  // namespace

std::string embedded_image_dir(const std::string& yaml_path) {
    return fs::path(yaml_path).stem().string() + "_textures";
}

std::vector<EmbeddedFile> embedded_files(const SceneDesc& d, const std::string& embedded_dir) {
    std::vector<EmbeddedFile> out;
    std::set<const EmbeddedImage*> seen;
    std::set<std::string> taken;
    for_each_texture(d, [&](const BitmapDesc& t) {
        if (!t.embedded || !seen.insert(t.embedded.get()).second) return;
        const std::string base = t.embedded->name.empty() ? "image" : t.embedded->name;
        std::string name = base;
        for (int n = 2; taken.count(name); ++n) name = numbered(base, n);
        taken.insert(name);
        out.push_back({embedded_dir.empty() ? name : embedded_dir + "/" + name, t.embedded});
    });
    return out;
}

std::string write_scene_yaml(const SceneDesc& d, const std::string& base_dir, const std::string& embedded_dir) {
    Names names{base_dir, {}};
    for (const EmbeddedFile& f : embedded_files(d, embedded_dir)) names.embedded[f.image.get()] = f.rel;
    std::string o;
    o += "# Scene format v1, written by omega";
    if (!d.path.empty()) o += " from " + d.path;
    o += "\n";
    for (const std::string& w : d.warnings) {
        std::string line = w;
        for (char& c : line)
            if (c == '\n' || c == '\r') c = ' ';
        o += "# warning: " + line + "\n";
    }
    o += "omega: 1\n";

    const IntegratorDesc& it = d.integrator;
    const char* itype = integrator_name(it.type);
    o += fmt::format("integrator: {{type: {}, max_depth: {}, rr_depth: {}}}\n", itype, it.max_depth, it.rr_depth);
    if (it.sampler != SamplerType::Sobol) o += fmt::format("sampler: {{type: {}}}\n", sampler_name(it.sampler));

    const SensorDesc& s = d.sensor;
    o += "sensor:\n";
    const char* stype = s.type == SensorType::Perspective ? "perspective"
                        : s.type == SensorType::ThinLens  ? "thin_lens"
                                                          : "orthographic";
    o += fmt::format("  type: {}\n", stype);
    if (s.type != SensorType::Orthographic) o += fmt::format("  fov: {}\n  fov_axis: {}\n", num(s.fov), s.fov_axis);
    if (s.type == SensorType::ThinLens)
        o += fmt::format("  aperture_radius: {}\n  focus_distance: {}\n", num(s.aperture_radius), num(s.focus_distance));
    o += fmt::format("  to_world: {}\n", matrix(s.to_world));
    if (s.near_clip != 0) o += fmt::format("  near_clip: {}\n", num(s.near_clip));
    if (std::isfinite(s.far_clip)) o += fmt::format("  far_clip: {}\n", num(s.far_clip));
    const FilmDesc& f = s.film;
    o += fmt::format("  film: {{width: {}, height: {}, filter: {}", f.width, f.height, filter_name(f.filter));
    if (f.filter == FilterType::Gaussian) o += fmt::format(", stddev: {}", num(f.gaussian_stddev));
    if (f.has_crop) o += fmt::format(", crop: [{}, {}, {}, {}]", f.crop[0], f.crop[1], f.crop[2], f.crop[3]);
    if (!f.aovs.empty()) {
        // Names are identifiers and expressions use no quote or backslash (the parser checked both).
        o += ", aov: {";
        for (size_t i = 0; i < f.aovs.size(); ++i)
            o += fmt::format("{}{}: \"{}\"", i ? ", " : "", f.aovs[i].name, f.aovs[i].expr);
        o += "}";
    }
    o += "}\n";
    if (s.halt.spp) o += fmt::format("  spp: {}\n", *s.halt.spp);
    if (s.halt.time_s) o += fmt::format("  time: {}\n", num(*s.halt.time_s));
    if (s.halt.target_error) o += fmt::format("  target_error: {}\n", num(*s.halt.target_error));

    // The parser's implicit default material is not written: shapes without `material` get it back.
    const std::string implicit = "(default)";
    bool any_material = false;
    for (const auto& [name, m] : d.materials) {
        if (name == implicit) continue;
        if (!any_material) o += "materials:\n";
        any_material = true;
        o += fmt::format("  {}: {}\n", q(name), material(m, names));
    }

    if (!d.shapes.empty()) o += "shapes:\n";
    for (const ShapeDesc& sh : d.shapes) {
        o += fmt::format("  - type: {}\n", shape_type(sh.type));
        if (!sh.name.empty()) o += fmt::format("    name: {}\n", q(sh.name));
        if (!is_identity(sh.to_world)) o += fmt::format("    to_world: {}\n", matrix(sh.to_world));
        if (sh.type == ShapeType::Sphere) o += fmt::format("    center: {}\n    radius: {}\n", vec(sh.center), num(sh.radius));
        if (sh.type == ShapeType::Mesh) {
            o += fmt::format("    file: {}\n", q(rel_path(sh.file, base_dir)));
            if (sh.face_normals) o += "    face_normals: true\n";
            if (!sh.flip_tex_coords) o += "    flip_tex_coords: false\n";
            if (!sh.drop_degenerate) o += "    drop_degenerate: false\n";
            if (!sh.mesh_parts.empty()) o += fmt::format("    meshes: [{}]\n", fmt::join(sh.mesh_parts, ", "));
        }
        if (sh.material != implicit) o += fmt::format("    material: {}\n", q(sh.material));
        if (sh.flip_normals) o += "    flip_normals: true\n";
        if (sh.emitter)
            o += fmt::format("    emitter: {{type: area, radiance: {}, two_sided: {}}}\n", rgb(sh.emitter->radiance),
                             sh.emitter->two_sided);
    }

    if (!d.lights.empty()) o += "lights:\n";
    for (const LightDesc& l : d.lights) {
        switch (l.type) {
            case LightType::Point:
                o += fmt::format("  - {{type: point, position: {}, intensity: {}}}\n", vec(l.position), rgb(l.intensity));
                break;
            case LightType::Spot:
                o += fmt::format("  - {{type: spot, to_world: {}, intensity: {}, cutoff_angle: {}, beam_width: {}}}\n",
                                 matrix(l.to_world), rgb(l.intensity), num(l.cutoff_angle), num(l.beam_width));
                break;
            case LightType::Directional:
                o += fmt::format("  - {{type: directional, direction: {}, irradiance: {}}}\n", vec(l.direction),
                                 rgb(l.irradiance));
                break;
            case LightType::Constant: o += fmt::format("  - {{type: constant, radiance: {}}}\n", rgb(l.radiance)); break;
            case LightType::EnvMap:
                o += fmt::format("  - {{type: envmap, file: {}, scale: {}", q(rel_path(l.file, base_dir)), num(l.scale));
                if (!is_identity(l.to_world)) o += fmt::format(", to_world: {}", matrix(l.to_world));
                o += "}\n";
                break;
        }
    }
    return o;
}

void write_scene_file(const SceneDesc& desc, const std::string& path) {
    fs::path dir = fs::path(path).parent_path();
    if (dir.empty()) dir = ".";
    const std::string images = embedded_image_dir(path);
    for (const EmbeddedFile& f : embedded_files(desc, images)) {
        std::error_code ec;
        fs::create_directories(dir / images, ec);
        if (ec) throw std::runtime_error("cannot create '" + (dir / images).string() + "': " + ec.message());
        write_file_atomically(dir / f.rel, f.image->bytes);
    }
    std::string text = write_scene_yaml(desc, dir.string(), images);
    std::ofstream out(path, std::ios::binary);
    if (!out) throw std::runtime_error("cannot write '" + path + "'");
    out << text;
    out.flush();
    if (!out) throw std::runtime_error("cannot write '" + path + "'");
}

}  // namespace omega
