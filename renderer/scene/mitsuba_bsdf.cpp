// The Mitsuba importer's BSDFs, colours and textures (mitsuba_importer_impl.h).
#include <fstream>
#include <functional>

#include "scene/blackbody.h"
#include "scene/mitsuba_importer_impl.h"
#include "scene/scene_files.h"
#include "texture/image.h"

namespace omega::mitsuba {

Rgb Importer::texture_average(pugi::xml_node tex, const std::string& key) {
    std::string type = attr(tex, "type", key);
    Elem e{tex, key, {}};
    if (type != "bitmap") {
        warn(tex, key, "texture type '" + type + "' is not supported; using its default grey 0.5");
        for (pugi::xml_node c : tex.children()) e.use(c);
        return {0.5f, 0.5f, 0.5f};
    }
    pugi::xml_node fn = find_param(e, "filename");
    if (!fn) fail(tex, key, "bitmap texture needs a 'filename' string");
    std::string file = attr(fn, "value", key + ".filename");
    fs::path p(file);
    if (p.is_relative()) p = dir_ / p;
    bool raw = false;
    if (auto r = find_param(e, "raw")) raw = attr(r, "value", key) == "true";
    for (const char* ignored : {"filter_type", "wrap_mode", "to_uv", "format", "accel"})
        if (auto c = find_param(e, ignored)) (void)c;  // sampling details of a texture Omega averages
    warn_unused(e);

    ImagePixels img = decode_image(gate(), p.string(), file, fmt::format("{}:{}: {}.filename: ", file_of(fn), line_of(fn), key));
    bool srgb = !raw && !img.is_float;
    const size_t nc = size_t(img.channels);
    double sum[3] = {0, 0, 0};
    size_t n = size_t(img.width) * size_t(img.height);
    for (size_t i = 0; i < n; ++i)
        for (int ch = 0; ch < 3; ++ch) {
            float v = img.data[i * nc + (nc >= 3 ? size_t(ch) : 0)];
            sum[ch] += srgb ? srgb_to_linear(v) : v;
        }
    Rgb avg{float(sum[0] / double(n)), float(sum[1] / double(n)), float(sum[2] / double(n))};
    for (int ch = 0; ch < 3; ++ch) avg[ch] = std::clamp(avg[ch], 0.f, 1.f);
    warn(tex, key,
         fmt::format("bitmap '{}': this parameter takes no texture in Omega (reflectances, transmittances, alpha and "
                     "a mask's opacity do); using its average colour [{:.4g}, {:.4g}, {:.4g}]{}",
                     file, avg.x, avg.y, avg.z, srgb ? " (sRGB-decoded)" : ""));
    return avg;
}

YAML::Node Importer::bitmap(pugi::xml_node tex, const std::string& key) {
    Elem e{tex, key, {}};
    YAML::Node y(YAML::NodeType::Map);
    y["type"] = "bitmap";
    pugi::xml_node fn = find_param(e, "filename");
    if (!fn) fail(tex, key, "bitmap texture needs a 'filename' string");
    // As written: the v1 parser resolves it against the XML file's folder, as Mitsuba does, and
    // checks it through the gate.
    y["file"] = attr(fn, "value", key + ".filename");
    if (auto c = find_param(e, "filter_type")) y["filter"] = attr(c, "value", key);
    if (auto c = find_param(e, "wrap_mode")) y["wrap"] = attr(c, "value", key);
    if (auto c = find_param(e, "raw")) y["raw"] = scalar(c, key);
    if (auto c = find_param(e, "to_uv"))
        if (YAML::Node t = to_uv(c, key); t.IsMap()) y["to_uv"] = t;
    // Storage and device details: the same texture values.
    for (const char* ignored : {"format", "accel"})
        if (auto c = find_param(e, ignored)) (void)c;
    warn_unused(e);
    return y;
}

YAML::Node Importer::to_uv(pugi::xml_node c, const std::string& key) {
    // Mitsuba reads to_uv as the 2D affine part (rows and columns x, y, w) of the 4x4 it builds.
    Mat4 m = to_world(c, key + ".to_uv");
    bool planar = m(0, 2) == 0 && m(1, 2) == 0 && m(2, 0) == 0 && m(2, 1) == 0;
    if (!planar) {
        warn(c, key, "to_uv mixes in the z axis, which a uv map does not have; it was ignored");
        return YAML::Node();  // null: the caller keeps identity
    }
    YAML::Node l(YAML::NodeType::Sequence);
    for (auto [r, col] : {std::pair{0, 0}, {0, 1}, {0, 3}, {1, 0}, {1, 1}, {1, 3}}) l.push_back(fmt::format("{}", m(r, col)));
    YAML::Node op(YAML::NodeType::Map);
    op["matrix"] = l;
    return op;
}

// Mitsuba's checkerboard (3 and 0.6: color0, color1, to_uv; defaults 0.4 and 0.2).
YAML::Node Importer::checkerboard(pugi::xml_node tex, const std::string& key) {
    Elem e{tex, key, {}};
    YAML::Node y(YAML::NodeType::Map);
    y["type"] = "checkerboard";
    for (const char* p : {"color0", "color1"})
        if (auto c = find_param(e, p)) y[p] = colour(c, key + "." + p);
    if (auto c = find_param(e, "to_uv"))
        if (YAML::Node t = to_uv(c, key); t.IsMap()) y["to_uv"] = t;
    warn_unused(e);
    return y;
}

YAML::Node Importer::colour(pugi::xml_node c, const std::string& key, bool texture_ok) {
    std::string tag = c.name();
    if (tag == "ref") {
        c = resolve_ref(c, key);
        tag = c.name();
    }
    if (tag == "texture" && texture_ok && attr(c, "type", key) == "bitmap") return bitmap(c, key);
    if (tag == "texture" && texture_ok && attr(c, "type", key) == "checkerboard") return checkerboard(c, key);
    if (tag == "texture") {
        Rgb a = texture_average(c, key);
        return list3(fmt::format("{}", a.x), fmt::format("{}", a.y), fmt::format("{}", a.z));
    }
    // A black body: Mitsuba 0.6's <blackbody temperature="5000K" scale="s"/>, or 3's
    // <spectrum type="blackbody"> with a <float name="temperature">. Units in scene/blackbody.h.
    if (tag == "blackbody" || (tag == "spectrum" && c.attribute("type"))) {
        std::string kelvin, scale = "1";
        if (tag == "blackbody") {
            kelvin = required_attr(c, "temperature", key);
            if (c.attribute("scale")) scale = attr(c, "scale", key);
        } else {
            std::string type = attr(c, "type", key);
            if (type != "blackbody") fail(c, key, "spectrum type '" + type + "' is not supported (blackbody is)");
            for (pugi::xml_node p : c.children())
                if (std::string(p.attribute("name").as_string()) == "temperature") kelvin = attr(p, "value", key);
            if (kelvin.empty()) fail(c, key, "a blackbody spectrum needs a temperature");
        }
        if (!kelvin.empty() && (kelvin.back() == 'K' || kelvin.back() == 'k')) kelvin.pop_back();
        const double t = to_double(kelvin, c, key), k = to_double(scale, c, key);
        if (!(t > 0)) fail(c, key, "a blackbody temperature must be positive, got " + kelvin);
        Rgb rgb = blackbody_linear_srgb(t);
        return list3(fmt::format("{}", k * std::max(0.f, rgb.x)), fmt::format("{}", k * std::max(0.f, rgb.y)),
                     fmt::format("{}", k * std::max(0.f, rgb.z)));
    }
    std::string v = attr(c, "value", key);
    if (tag == "float") return YAML::Node(v);
    if (tag == "rgb" || tag == "srgb") {
        std::vector<std::string> parts;
        if (!v.empty() && v[0] == '#') {
            if (v.size() != 7) fail(c, key, "expected #rrggbb, got '" + v + "'");
            for (int i = 0; i < 3; ++i) {
                int x = std::stoi(v.substr(size_t(1 + 2 * i), 2), nullptr, 16);
                parts.push_back(fmt::format("{}", srgb_to_linear(float(x) / 255.f)));
            }
            return list3(parts[0], parts[1], parts[2]);
        }
        parts = split_numbers(v);
        if (parts.size() == 1) parts = {parts[0], parts[0], parts[0]};
        if (parts.size() != 3) fail(c, key, "expected 1 or 3 numbers, got '" + v + "'");
        if (tag == "srgb")
            for (auto& p : parts) p = fmt::format("{}", srgb_to_linear(float(to_double(p, c, key))));
        return list3(parts[0], parts[1], parts[2]);
    }
    if (tag == "spectrum") {
        auto parts = split_numbers(v);
        if (parts.size() == 1 && parts[0].find(':') == std::string::npos) return YAML::Node(parts[0]);
        // Mitsuba 0.x's default build has 3 spectral samples, its RGB: Bitterli's 0.6 files rely on it.
        if (legacy_ && parts.size() == 3 && v.find(':') == std::string::npos) return list3(parts[0], parts[1], parts[2]);
        // Wavelength:value pairs: Omega is RGB; the flat average is the best it can do.
        double sum = 0;
        int n = 0;
        for (const auto& p : parts) {
            size_t colon = p.find(':');
            if (colon == std::string::npos) fail(c, key, "expected a number or wavelength:value pairs, got '" + v + "'");
            sum += to_double(p.substr(colon + 1), c, key);
            ++n;
        }
        if (n == 0) fail(c, key, "empty spectrum");
        warn(c, key, "a sampled spectrum is approximated by its average value (Omega renders RGB)");
        return YAML::Node(fmt::format("{}", sum / n));
    }
    fail(c, key, "expected a colour (<rgb>, <spectrum>, <blackbody>, <float> or a bitmap <texture>), got <" + tag + ">");
}

// A bsdf element as a YAML material mapping (for parse_material_value).
YAML::Node Importer::read_bsdf(pugi::xml_node n, const std::string& key, bool two_sided,
                               std::map<std::string, int>& lines) {
    std::string type = attr(n, "type", key);
    Elem e{n, key, {}};
    YAML::Node y(YAML::NodeType::Map);
    auto put = [&](const char* yaml_key, const char* xml_name) {
        if (auto c = find_param(e, xml_name)) {
            y[yaml_key] = c.name() == std::string("string") ? YAML::Node(attr(c, "value", key)) : scalar(c, key);
            lines[yaml_key] = line_of(c);
        }
    };
    auto put_colour = [&](const char* yaml_key, const char* xml_name, bool texture_ok = false) {
        if (auto c = find_param(e, xml_name)) {
            y[yaml_key] = colour(c, key + "." + xml_name, texture_ok);
            lines[yaml_key] = line_of(c);
        }
    };
    auto nested = [&]() -> pugi::xml_node {
        for (pugi::xml_node c : n.children()) {
            std::string t = c.name();
            if (t == "bsdf") {
                e.use(c);
                return c;
            }
            if (t == "ref") {
                pugi::xml_node r = resolve_ref(c, key);
                if (std::string(r.name()) == "bsdf") {
                    e.use(c);
                    return r;
                }
            }
        }
        return {};
    };
    auto put_alpha = [&](const char* def) {
        bool any = false;
        for (const char* p : {"alpha", "alpha_u", "alpha_v"})
            if (auto c = find_param(e, p)) {
                const bool tex = std::string(c.name()) == "texture" || std::string(c.name()) == "ref";
                if (tex && std::string(p) == "alpha") {
                    y[p] = colour(c, key + ".alpha", true);  // a roughness texture, looked up per hit
                } else if (tex) {
                    warn(c, key, std::string(p) + " textures are not supported (an isotropic alpha texture is); using " + p +
                                     " " + def);
                    y[p] = def;
                } else {
                    y[p] = scalar(c, key);
                }
                lines[p] = line_of(c);
                any = true;
            }
        if (!any) y["alpha"] = def;  // Mitsuba's default roughness
        if (auto c = find_param(e, "distribution")) {
            y["distribution"] = attr(c, "value", key);
            lines["distribution"] = line_of(c);
        } else {
            y["distribution"] = "beckmann";  // Mitsuba's default
        }
        if (auto c = find_param(e, "sample_visible")) (void)c;  // sampling only: same expectation
    };
    auto put_conductor = [&] {
        y["type"] = "conductor";
        if (auto c = find_param(e, "material")) {
            std::string m = attr(c, "value", key);
            lines["material"] = line_of(c);
            if (m == "Au" || m == "Ag" || m == "Cu" || m == "Al") y["material"] = m;
            else if (m != "none")
                warn(c, key, "conductor material '" + m + "' is not tabulated in Omega (Au, Ag, Cu, Al); using a perfect mirror");
        }
        put_colour("eta", "eta");
        put_colour("k", "k");
        put_colour("specular_reflectance", "specular_reflectance", true);
        y["two_sided"] = two_sided;
    };

    if (type == "twosided") {
        pugi::xml_node inner = nested();
        if (!inner) fail(n, key, "twosided needs a nested <bsdf>");
        int count = 0;
        for (pugi::xml_node c : n.children())
            if (std::string(c.name()) == "bsdf" || std::string(c.name()) == "ref") ++count;
        if (count > 1) warn(n, key, "twosided with two different BSDFs is not supported; the front one is used on both sides");
        for (pugi::xml_node c : n.children()) e.use(c);
        return read_bsdf(inner, key, true, lines);
    }
    if (type == "mask") {
        // Mitsuba's mask: the nested BSDF with probability `opacity` (default 0.5 in 3 and 0.6),
        // a pass-through otherwise; Omega keeps the opacity on the material (Scene::intersect).
        pugi::xml_node inner = nested();
        if (!inner) fail(n, key, "mask needs a nested <bsdf>");
        pugi::xml_node op = find_param(e, "opacity");
        warn_unused(e);
        y = read_bsdf(inner, key, two_sided, lines);
        if (static_cast<const YAML::Node&>(y)["opacity"]) fail(n, key, "nested masks are not supported");
        y["opacity"] = op ? colour(op, key + ".opacity", true) : YAML::Node("0.5");
        if (op) lines["opacity"] = line_of(op);
        return y;
    }
    if (type == "bumpmap") {
        // Mitsuba's bumpmap (3 and 0.6): a nested height texture of any name (the first), `scale`
        // (default 1), and the nested BSDF shaded with the tilted normal.
        pugi::xml_node inner = nested();
        if (!inner) fail(n, key, "bumpmap needs a nested <bsdf>");
        pugi::xml_node tex;
        for (pugi::xml_node c : n.children()) {
            std::string t = c.name();
            pugi::xml_node r = t == "ref" ? resolve_ref(c, key) : c;
            if (std::string(r.name()) == "texture" && !tex) {
                e.use(c);
                tex = r;
            }
        }
        if (!tex) fail(n, key, "bumpmap needs a nested height <texture>");
        pugi::xml_node sc = find_param(e, "scale");
        warn_unused(e);
        y = read_bsdf(inner, key, two_sided, lines);
        if (static_cast<const YAML::Node&>(y)["bump"]) fail(n, key, "nested bump maps are not supported");
        std::string ttype = attr(tex, "type", key);
        if (ttype == "bitmap") y["bump"] = bitmap(tex, key + ".height");
        else if (ttype == "checkerboard") y["bump"] = checkerboard(tex, key + ".height");
        else fail(tex, key, "a bumpmap height texture of type '" + ttype + "' is not supported (bitmap, checkerboard)");
        y["bump_scale"] = sc ? scalar(sc, key) : YAML::Node("1");
        if (sc) lines["bump_scale"] = line_of(sc);
        return y;
    }
    if (type == "diffuse") {
        y["type"] = "diffuse";
        put_colour("reflectance", "reflectance", true);
        y["two_sided"] = two_sided;
    } else if (type == "roughdiffuse") {
        // Mitsuba 0.6 (Oren-Nayar; bsdf/diffuse.cpp): reflectance or diffuse_reflectance, alpha
        // (default 0.2), use_fast_approx (default false).
        y["type"] = "roughdiffuse";
        put_colour("reflectance", "reflectance", true);
        if (!lines.count("reflectance")) put_colour("reflectance", "diffuse_reflectance", true);
        if (auto c = find_param(e, "alpha")) {
            const bool tex = std::string(c.name()) == "texture" || std::string(c.name()) == "ref";
            y["alpha"] = tex ? colour(c, key + ".alpha", true) : scalar(c, key);
            lines["alpha"] = line_of(c);
        } else {
            y["alpha"] = "0.2";  // Mitsuba's default
        }
        put("fast_approx", "use_fast_approx");
        y["two_sided"] = two_sided;
    } else if (type == "conductor") {
        put_conductor();
    } else if (type == "roughconductor") {
        put_conductor();
        put_alpha("0.1");
    } else if (type == "dielectric" || type == "roughdielectric" || type == "thindielectric") {
        // Mitsuba 3 and 0.6 share the parameters and defaults (BK7 in air, Ks = Kt = 1).
        y["type"] = type == "thindielectric" ? "thindielectric" : "dielectric";
        for (const char* p : {"int_ior", "ext_ior"}) put(p, p);
        put_colour("specular_reflectance", "specular_reflectance", true);
        put_colour("specular_transmittance", "specular_transmittance", true);
        if (type == "roughdielectric") put_alpha("0.1");
    } else if (type == "plastic" || type == "roughplastic") {
        // Mitsuba 3 and 0.6 share the model and the defaults (polypropylene in air, nonlinear
        // false, diffuse 0.5, specular 1; roughplastic: Beckmann, alpha 0.1); written out
        // explicitly so that Omega's own defaults never leak into an imported scene.
        y["type"] = type;
        put_colour("diffuse_reflectance", "diffuse_reflectance", true);
        if (!lines.count("diffuse_reflectance")) y["diffuse_reflectance"] = "0.5";
        put_colour("specular_reflectance", "specular_reflectance", true);
        put("int_ior", "int_ior");
        if (!lines.count("int_ior")) y["int_ior"] = "polypropylene";
        put("ext_ior", "ext_ior");
        if (!lines.count("ext_ior")) y["ext_ior"] = "air";
        put("nonlinear", "nonlinear");
        if (type == "roughplastic") put_alpha("0.1");
        y["two_sided"] = two_sided;
    } else if (type == "null") {
        y["type"] = "black";
        warn(n, key, "the null BSDF (an invisible surface) is not supported; the surface is black instead");
    } else {
        pugi::xml_node inner = nested();
        if (inner) {
            warn(n, key, "BSDF '" + type + "' is not supported; using its nested BSDF");
            for (pugi::xml_node c : n.children()) e.use(c);
            return read_bsdf(inner, key, two_sided, lines);
        }
        warn(n, key, "BSDF '" + type + "' is not supported; using a grey diffuse BSDF (reflectance 0.5)");
        for (pugi::xml_node c : n.children()) e.use(c);
        y["type"] = "diffuse";
        y["two_sided"] = two_sided;
    }
    warn_unused(e);
    return y;
}

std::string Importer::material_for(pugi::xml_node bsdf, const std::string& fallback_name) {
    std::string id = bsdf.attribute("id") ? attr(bsdf, "id", fallback_name) : "";
    if (!id.empty()) {
        referenced_ids_.insert(id);
        if (auto it = material_of_id_.find(id); it != material_of_id_.end()) return it->second;
    }
    std::string name = id.empty() ? fallback_name : id;
    while (desc_.materials.count(name)) name += "'";
    std::string key = id.empty() ? fallback_name : "bsdf(" + id + ")";
    std::map<std::string, int> lines;
    YAML::Node y = read_bsdf(bsdf, key, false, lines);
    MaterialDesc m = checked(key, bsdf, lines, [&](ParamValue v) {
        return parse_material_value(ParamValue(y, v.path(), fname_of(bsdf), v.line()), name, desc_.warnings);
    });
    m.loc = {file_of(bsdf), line_of(bsdf), key};
    desc_.materials[name] = m;
    if (!id.empty()) material_of_id_[id] = name;
    return name;
}

}  // namespace omega::mitsuba
