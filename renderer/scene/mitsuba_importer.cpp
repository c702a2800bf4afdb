#include "scene/mitsuba_importer.h"
#include "scene/gltf_importer.h"
#include "scene/mitsuba_importer_impl.h"

#include <fmt/format.h>
#include <pugixml.hpp>
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <set>
#include <sstream>

#include "io/file_gate.h"
#include "scene/param_bag.h"
#include "scene/scene_files.h"
#include "texture/image.h"
#include "scene/scene_parser.h"

namespace omega {

namespace mitsuba {

// Mitsuba 0.x spelled parameters in camelCase (toWorld, maxDepth, intIOR); 3.x uses snake_case.
std::string snake_case(const std::string& s) {
    std::string out;
    for (size_t i = 0; i < s.size(); ++i) {
        char c = s[i];
        if (std::isupper(static_cast<unsigned char>(c))) {
            bool prev_upper = i > 0 && std::isupper(static_cast<unsigned char>(s[i - 1]));
            if (i > 0 && !prev_upper) out += '_';
            out += char(std::tolower(static_cast<unsigned char>(c)));
        } else {
            out += c;
        }
    }
    return out;
}

std::vector<std::string> split_numbers(const std::string& s) {
    std::vector<std::string> out;
    std::string cur;
    for (char c : s) {
        if (c == ',' || std::isspace(static_cast<unsigned char>(c))) {
            if (!cur.empty()) out.push_back(cur);
            cur.clear();
        } else {
            cur += c;
        }
    }
    if (!cur.empty()) out.push_back(cur);
    return out;
}
void Importer::warn_unused(Elem& e, const std::string& what) {
    for (pugi::xml_node c : e.node.children()) {
        if (c.type() != pugi::node_element || e.used.count(size_t(c.offset_debug()))) continue;
        std::string name = c.attribute("name") ? attr(c, "name", e.key) : "";
        std::string tag = c.name();
        if (!name.empty())
            warn(c, e.key, fmt::format("{} '{}' (<{}>) is not supported and was ignored", what, name, tag));
        else
            warn(c, e.key, fmt::format("<{}{}> is not supported here and was ignored", tag,
                                       c.attribute("type") ? fmt::format(" type=\"{}\"", attr(c, "type", e.key)) : ""));
    }
}

YAML::Node Importer::transform_ops(pugi::xml_node t, const std::string& key) {
    YAML::Node ops(YAML::NodeType::Sequence);
    for (pugi::xml_node op : t.children()) {
        if (op.type() != pugi::node_element) continue;
        std::string tag = op.name();
        YAML::Node m(YAML::NodeType::Map);
        if (tag == "matrix") {
            auto parts = split_numbers(required_attr(op, "value", key));
            if (parts.size() == 9) {  // 3x3: linear part only
                parts = {parts[0], parts[1], parts[2], "0", parts[3], parts[4], parts[5], "0",
                         parts[6], parts[7], parts[8], "0", "0",      "0",      "0",      "1"};
            }
            if (parts.size() != 16) fail(op, key, fmt::format("<matrix> needs 16 numbers, got {}", parts.size()));
            YAML::Node l(YAML::NodeType::Sequence);
            for (auto& p : parts) l.push_back(p);
            m["matrix"] = l;
        } else if (tag == "lookat" || tag == "look_at") {
            auto vec = [&](const char* a) {
                auto parts = split_numbers(required_attr(op, a, key));
                if (parts.size() != 3) fail(op, key, fmt::format("lookat {} needs 3 numbers", a));
                return list3(parts[0], parts[1], parts[2]);
            };
            YAML::Node la(YAML::NodeType::Map);
            la["origin"] = vec("origin");
            la["target"] = vec("target");
            la["up"] = op.attribute("up") ? vec("up") : list3("0", "1", "0");
            m["look_at"] = la;
        } else if (tag == "translate") {
            m["translate"] = vec_node(vec3(op, key));
        } else if (tag == "scale") {
            if (op.attribute("value") && split_numbers(attr(op, "value", key)).size() == 1)
                m["scale"] = attr(op, "value", key);
            else if (op.attribute("value"))
                m["scale"] = vec_node(vec3(op, key));
            else
                m["scale"] = vec_node({op.attribute("x") ? to_double(attr(op, "x", key), op, key) : 1.0,
                                       op.attribute("y") ? to_double(attr(op, "y", key), op, key) : 1.0,
                                       op.attribute("z") ? to_double(attr(op, "z", key), op, key) : 1.0});
        } else if (tag == "rotate") {
            YAML::Node r(YAML::NodeType::Map);
            r["axis"] = vec_node(vec3(op, key));  // x, y, z attributes or value="x y z"
            r["angle"] = required_attr(op, "angle", key);
            m["rotate"] = r;
        } else {
            warn(op, key, "transform operation <" + tag + "> is not supported and was ignored");
            continue;
        }
        ops.push_back(m);
    }
    return ops;
}

void Importer::read_defaults(pugi::xml_node scene) {
    vars_ = opt_.defines;
    for (pugi::xml_node d : scene.children("default")) {
        std::string name = d.attribute("name").as_string();
        if (name.empty()) fail(d, "default", "<default> needs a 'name' attribute");
        if (!d.attribute("value")) fail(d, "default", "<default> needs a 'value' attribute");
        if (!vars_.count(name)) vars_[name] = d.attribute("value").as_string();
    }
}

void Importer::warn_unused_defines(pugi::xml_node scene) {
    for (const auto& [name, value] : opt_.defines) {
        bool declared = false;
        for (pugi::xml_node d : scene.children("default")) declared |= name == d.attribute("name").as_string();
        bool used = false;
        for (const auto& src : sources_) used |= src->text.find("$" + name) != std::string::npos;
        if (!declared && !used)
            desc_.warnings.push_back(fmt::format("{}:1: define {}={} is not used by the scene", file_, name, value));
    }
}

void Importer::read_integrator(pugi::xml_node n) {
    std::string key = "integrator";
    Elem e{n, key, {}};
    std::string type = attr(n, "type", key);
    YAML::Node y(YAML::NodeType::Map);
    std::map<std::string, int> lines;
    if (type == "path" || type == "bdpt" || type == "ptracer") {
        y["type"] = type == "ptracer" ? "light" : type;
    } else {
        y["type"] = "path";
        warn(n, key, "integrator '" + type + "' is not supported; using Omega's path tracer (pass --integrator to choose)");
    }
    for (const char* p : {"max_depth", "rr_depth"})
        if (auto c = find_param(e, p)) {
            y[p] = scalar(c, key);
            lines[p] = line_of(c);
        }
    if (auto c = find_param(e, "hide_emitters"))
        if (attr(c, "value", key) == "true") warn(c, key, "hide_emitters is not supported; emitters stay visible");
    // Omega's walks always drop a direction whose side the shading and geometric normals disagree
    // on, which is what strictNormals asks for (0.6 exports set it).
    if (auto c = find_param(e, "strict_normals"))
        if (attr(c, "value", key) != "true")
            warn(c, key, "strict_normals false is not supported: Omega always discards paths whose shading and "
                         "geometric normals disagree about the side");
    warn_unused(e);
    desc_.integrator = checked(key, n, lines, [&](ParamValue v) {
        return parse_integrator_value(ParamValue(y, v.path(), fname_of(n), v.line()));
    });
}

void Importer::read_sensor(pugi::xml_node n) {
    std::string key = "sensor";
    Elem e{n, key, {}};
    std::string type = attr(n, "type", key);
    YAML::Node y(YAML::NodeType::Map);
    std::map<std::string, int> lines;
    if (type == "perspective") y["type"] = "perspective";
    else if (type == "thinlens") y["type"] = "thin_lens";
    else if (type == "orthographic") y["type"] = "orthographic";
    else {
        y["type"] = "perspective";
        warn(n, key, "sensor '" + type + "' is not supported; using a perspective camera");
    }
    bool ortho = type == "orthographic";

    // Film first: fov_axis conversions need the aspect ratio.
    int width = 768, height = 576;  // Mitsuba's hdrfilm defaults
    YAML::Node film(YAML::NodeType::Map);
    YAML::Node filter_node = YAML::Node("gaussian");  // Mitsuba's default reconstruction filter
    pugi::xml_node film_el = n.child("film");
    if (film_el) {
        e.use(film_el);
        std::string fkey = key + ".film";
        Elem f{film_el, fkey, {}};
        std::string ftype = attr(film_el, "type", fkey);
        // ldrfilm (Bitterli's 0.6 exports) is the same radiance estimate, tone-mapped on output;
        // Omega's output is always the HDR image, so its tone-mapping parameters have nothing to
        // change (docs/scene-format.md, "Mitsuba XML").
        const bool ldr = ftype == "ldrfilm";
        if (ftype != "hdrfilm" && !ldr)
            warn(film_el, fkey, "film '" + ftype + "' is not supported; using an RGB EXR film");
        lines["film"] = line_of(film_el);
        if (auto c = find_param(f, "width")) width = integer(c, fkey);
        if (auto c = find_param(f, "height")) height = integer(c, fkey);
        for (const char* fmt_key : {"file_format", "pixel_format", "component_format"}) {
            if (auto c = find_param(f, fmt_key)) {
                std::string v = attr(c, "value", fkey);
                static const std::set<std::string> ok = {"openexr", "exr", "rgb", "rgba", "float16", "float32"};
                if (!ok.count(v) && !ldr)
                    warn(c, fkey, fmt::format("{} '{}' is not supported; Omega writes RGB float EXR", fmt_key, v));
            }
        }
        if (ldr)
            for (const char* p : {"gamma", "exposure", "tonemap_method", "key", "burn", "banner", "high_quality_edges"})
                (void)find_param(f, p);
        int cx = 0, cy = 0, cw = width, ch = height;
        bool crop = false;
        if (auto c = find_param(f, "crop_offset_x")) cx = integer(c, fkey), crop = true;
        if (auto c = find_param(f, "crop_offset_y")) cy = integer(c, fkey), crop = true;
        if (auto c = find_param(f, "crop_width")) cw = integer(c, fkey), crop = true;
        if (auto c = find_param(f, "crop_height")) ch = integer(c, fkey), crop = true;
        if (crop) {
            YAML::Node cr(YAML::NodeType::Sequence);
            for (int v : {cx, cy, cx + cw, cy + ch}) cr.push_back(v);
            film["crop"] = cr;
        }
        if (pugi::xml_node rf = film_el.child("rfilter")) {
            f.use(rf);
            std::string rkey = fkey + ".rfilter";
            Elem r{rf, rkey, {}};
            std::string rtype = attr(rf, "type", rkey);
            if (rtype == "box" || rtype == "tent" || rtype == "gaussian") {
                filter_node = YAML::Node(rtype);
                if (rtype == "gaussian")
                    if (auto c = find_param(r, "stddev")) film["stddev"] = scalar(c, rkey);
                if (rtype == "tent")
                    if (auto c = find_param(r, "radius"))
                        if (number(c, rkey) != 1.0) warn(c, rkey, "tent radius other than 1 is not supported; using 1");
            } else {
                filter_node = YAML::Node("gaussian");
                warn(rf, rkey, "reconstruction filter '" + rtype + "' is not supported; using a gaussian (stddev 0.5)");
            }
            warn_unused(r);
        }
        warn_unused(f);
    }
    film["width"] = width;
    film["height"] = height;
    film["filter"] = filter_node;
    y["film"] = film;

    if (!ortho) {
        pugi::xml_node fovn = find_param(e, "fov");
        double fov = 0;
        if (fovn) {
            fov = number(fovn, key);
            lines["fov"] = line_of(fovn);
        } else {
            // Mitsuba's default: a 50 mm lens on 36 x 24 mm film, i.e. the diagonal field of view.
            if (auto fl = find_param(e, "focal_length"))
                warn(fl, key, "focal_length is not supported; using fov with Mitsuba's 50mm default instead");
            fov = 2 * std::atan(std::sqrt(36.0 * 36.0 + 24.0 * 24.0) / (2 * 50.0)) * 180 / kPi;
            warn(n, key, fmt::format("no fov given: using Mitsuba's default (50 mm lens, {:.4g} degrees diagonal)", fov));
        }
        std::string axis = "x";
        if (auto c = find_param(e, "fov_axis")) axis = attr(c, "value", key), lines["fov_axis"] = line_of(c);
        else if (!fovn) axis = "diagonal";
        double t = std::tan(fov * kPi / 360);
        if (axis == "smaller") axis = width <= height ? "x" : "y";
        if (axis == "larger") axis = width >= height ? "x" : "y";
        if (axis == "diagonal") {
            if (!(fov > 0 && fov < 180)) fail(fovn ? fovn : n, key + ".fov", fmt::format("must be in (0, 180), got {}", fov));
            double fx = 2 * std::atan(t * width / std::hypot(double(width), double(height))) * 180 / kPi;
            y["fov"] = fmt::format("{}", fx);
            y["fov_axis"] = "x";
        } else {
            y["fov"] = fovn ? attr(fovn, "value", key) : fmt::format("{}", fov);
            y["fov_axis"] = axis;  // x or y; anything else fails in the sensor parser
        }
    }
    if (type == "thinlens") {
        for (const char* p : {"aperture_radius", "focus_distance"})
            if (auto c = find_param(e, p)) y[p] = scalar(c, key), lines[p] = line_of(c);
    } else {
        (void)find_param(e, "focus_distance");  // a pinhole is in focus everywhere (0.6 exports write it)
    }
    if (auto c = find_param(e, "near_clip")) y["near_clip"] = scalar(c, key), lines["near_clip"] = line_of(c);
    // Omega does not clip far away; the scene build warns if any geometry lies beyond far_clip.
    if (auto c = find_param(e, "far_clip")) y["far_clip"] = scalar(c, key), lines["far_clip"] = line_of(c);
    if (auto c = find_param(e, "to_world")) {
        Mat4 m = to_world(c, key + ".to_world");
        YAML::Node l(YAML::NodeType::Sequence);
        for (double x : m.m) l.push_back(fmt::format("{}", x));
        YAML::Node mm(YAML::NodeType::Map);
        mm["matrix"] = l;
        y["to_world"] = mm;
    }
    if (pugi::xml_node s = n.child("sampler")) {
        e.use(s);
        std::string skey = key + ".sampler";
        Elem se{s, skey, {}};
        std::string stype = attr(s, "type", skey);
        if (stype != "independent")
            warn(s, skey, "sampler '" + stype + "' is replaced by Omega's independent sampler (same expectation)");
        if (auto c = find_param(se, "sample_count")) y["spp"] = scalar(c, skey), lines["spp"] = line_of(c);
        if (auto c = find_param(se, "seed")) warn(c, skey, "the sampler seed is ignored; use --seed");
        warn_unused(se);
    }
    warn_unused(e);
    desc_.sensor = checked(key, n, lines, [&](ParamValue v) {
        return parse_sensor_value(ParamValue(y, v.path(), fname_of(n), v.line()));
    });
    desc_.sensor.loc = {file_of(n), line_of(n), key};
}

void Importer::read_shape(pugi::xml_node n, size_t index) {
    std::string key = elem_key(n, "shape", index);
    Elem e{n, key, {}};
    std::string type = attr(n, "type", key);
    ShapeDesc s;
    s.loc = {file_of(n), line_of(n), key};
    s.name = n.attribute("id") ? attr(n, "id", key) : "";
    if (type == "rectangle") s.type = ShapeType::Rectangle;
    else if (type == "cube") s.type = ShapeType::Cube;
    else if (type == "sphere") s.type = ShapeType::Sphere;
    else if (type == "disk") s.type = ShapeType::Disk;
    else if (type == "obj" || type == "ply") s.type = ShapeType::Mesh;
    else {
        warn(n, key, "shape '" + type + "' is not supported; it was skipped");
        return;
    }
    if (auto c = find_param(e, "to_world")) s.to_world = to_world(c, key + ".to_world");
    if (s.type == ShapeType::Sphere) {
        if (auto c = find_param(e, "center")) s.center = vec3(c, key + ".center");
        if (auto c = find_param(e, "radius")) {
            s.radius = number(c, key + ".radius");
            if (!(s.radius > 0)) fail(c, key + ".radius", fmt::format("must be > 0, got {}", s.radius));
        }
    }
    if (s.type == ShapeType::Mesh) {
        pugi::xml_node fnode = find_param(e, "filename");
        if (!fnode) fail(n, key, "a " + type + " shape needs a 'filename' string");
        std::string file = attr(fnode, "value", key + ".filename");
        fs::path p(file);
        if (p.is_relative()) p = dir_ / p;
        std::error_code ec;
        fs::path abs = fs::absolute(p, ec);
        s.file = (ec ? p : abs).lexically_normal().string();
        s.written = file;
        s.file_loc = {file_of(fnode), line_of(fnode), key + ".filename"};  // checked through the gate in run()
        if (auto c = find_param(e, "face_normals")) s.face_normals = attr(c, "value", key) == "true";
        if (auto c = find_param(e, "flip_tex_coords")) s.flip_tex_coords = attr(c, "value", key) != "false";
    }
    if (auto c = find_param(e, "flip_normals")) s.flip_normals = attr(c, "value", key) == "true";

    std::string material;
    for (pugi::xml_node c : n.children()) {
        std::string tag = c.name();
        pugi::xml_node target = c;
        if (tag == "ref") {
            target = resolve_ref(c, key);
            tag = target.name();
            if (tag != "bsdf" && tag != "emitter") continue;  // left for warn_unused
        }
        if (tag == "bsdf") {
            e.use(c);
            if (!material.empty()) {
                warn(c, key, "a second BSDF on one shape was ignored");
                continue;
            }
            material = material_for(target, (s.name.empty() ? key : s.name) + ".bsdf");
        } else if (tag == "emitter") {
            e.use(c);
            std::string ekey = key + ".emitter";
            std::string etype = attr(target, "type", ekey);
            if (etype != "area") {
                warn(target, ekey, "emitter '" + etype + "' cannot be attached to a shape; it was skipped");
                continue;
            }
            Elem ee{target, ekey, {}};
            YAML::Node y(YAML::NodeType::Map);
            std::map<std::string, int> lines;
            y["type"] = "area";
            if (auto r = find_param(ee, "radiance")) y["radiance"] = colour(r, ekey + ".radiance"), lines["radiance"] = line_of(r);
            if (auto r = find_param(ee, "sampling_weight")) warn(r, ekey, "sampling_weight is ignored (lights are chosen by power)");
            warn_unused(ee);
            s.emitter = checked(ekey, target, lines, [&](ParamValue v) {
                return parse_emitter_value(ParamValue(y, v.path(), fname_of(target), v.line()));
            });
        }
    }
    if (material.empty()) {
        // Mitsuba's default BSDF: a one-sided grey diffuse.
        const std::string name = "default_diffuse";
        if (!desc_.materials.count(name)) desc_.materials[name] = MaterialDesc{name, DiffuseBsdf{{0.5f, 0.5f, 0.5f}, false}, s.loc};
        material = name;
    }
    s.material = material;
    warn_unused(e);
    desc_.shapes.push_back(std::move(s));
}

void Importer::read_emitter(pugi::xml_node n, size_t index) {
    std::string key = elem_key(n, "emitter", index);
    Elem e{n, key, {}};
    std::string type = attr(n, "type", key);
    YAML::Node y(YAML::NodeType::Map);
    std::map<std::string, int> lines;
    auto put_colour = [&](const char* yaml_key, const char* xml_name) {
        if (auto c = find_param(e, xml_name)) y[yaml_key] = colour(c, key + "." + xml_name), lines[yaml_key] = line_of(c);
    };
    if (type == "point") {
        y["type"] = "point";
        Vec3d pos{0, 0, 0};
        if (auto c = find_param(e, "position")) pos = vec3(c, key + ".position");
        if (auto c = find_param(e, "to_world")) pos = to_world(c, key + ".to_world").point(pos);
        y["position"] = vec_node(pos);
        put_colour("intensity", "intensity");
    } else if (type == "spot") {
        y["type"] = "spot";
        if (auto c = find_param(e, "to_world")) {
            Mat4 m = to_world(c, key + ".to_world");
            YAML::Node l(YAML::NodeType::Sequence);
            for (double x : m.m) l.push_back(fmt::format("{}", x));
            y["to_world"]["matrix"] = l;
        }
        put_colour("intensity", "intensity");
        for (const char* p : {"cutoff_angle", "beam_width"})
            if (auto c = find_param(e, p)) y[p] = scalar(c, key), lines[p] = line_of(c);
    } else if (type == "directional") {
        y["type"] = "directional";
        Vec3d d{0, 0, 1};
        if (auto c = find_param(e, "direction")) d = vec3(c, key + ".direction");
        if (auto c = find_param(e, "to_world")) d = to_world(c, key + ".to_world").vector(d);
        y["direction"] = vec_node(d);
        put_colour("irradiance", "irradiance");
    } else if (type == "constant") {
        y["type"] = "constant";
        put_colour("radiance", "radiance");
    } else if (type == "envmap") {
        // An image-based environment (light/envmap.h follows Mitsuba 3's mapping). The file as
        // written: the v1 parser resolves it against the XML file's folder and checks it
        // through the gate; Scene::build reads it.
        pugi::xml_node fn = find_param(e, "filename");
        if (!fn) fail(n, key, "envmap needs a 'filename' string");
        y["type"] = "envmap";
        // Relative to the main scene's folder, as every file is (Mitsuba's resolver), written
        // relative to the folder of the file that names it, which the v1 parser resolves against.
        const std::string written = attr(fn, "value", key + ".filename");
        fs::path file(written);
        if (file.is_relative()) {
            fs::path base = fs::path(file_of(n)).parent_path();
            fs::path rel = (dir_ / file).lexically_normal().lexically_relative(base.empty() ? fs::path(".") : base);
            file = rel.empty() ? (dir_ / file).lexically_normal() : rel;
        }
        y["file"] = file.string();
        lines["file"] = line_of(fn);
        if (auto c = find_param(e, "scale")) y["scale"] = scalar(c, key), lines["scale"] = line_of(c);
        if (auto c = find_param(e, "to_world")) {
            Mat4 m = to_world(c, key + ".to_world");
            YAML::Node l(YAML::NodeType::Sequence);
            for (double x : m.m) l.push_back(fmt::format("{}", x));
            y["to_world"]["matrix"] = l;
        }
        if (auto c = find_param(e, "filter_type"); c && attr(c, "value", key) != "bilinear")
            warn(c, key, "envmap filter_type '" + attr(c, "value", key) + "' is not supported; bilinear is used");
        if (auto c = find_param(e, "mis_compensation")) (void)c;  // a sampling detail: the image is the same
    } else {
        warn(n, key, "emitter '" + type + "' is not supported; it was skipped");
        return;
    }
    if (auto c = find_param(e, "sampling_weight")) warn(c, key, "sampling_weight is ignored (lights are chosen by power)");
    warn_unused(e);
    LightDesc l = checked(key, n, lines, [&](ParamValue v) {
        return parse_light_value(ParamValue(y, v.path(), fname_of(n), v.line()));
    });
    l.loc = {file_of(n), line_of(n), key};
    desc_.lights.push_back(l);
}

namespace {
// Parses one file's text into its document, or names the file and line of the XML error.
void parse_source(Source& src) {
    pugi::xml_parse_result res =
        src.doc->load_buffer(src.text.data(), src.text.size(), pugi::parse_default, pugi::encoding_utf8);
    if (!res)
        throw SceneError(fmt::format("{}:{}: invalid XML: {}", src.file,
                                     src.line_at(size_t(std::max<ptrdiff_t>(0, res.offset))), res.description()));
    if (!src.doc->child("scene"))
        throw SceneError(fmt::format("{}:1: scene: the root element must be <scene>", src.file));
}
// Includes nest at most this deep: deeper is a cycle the path check missed, or abuse.
constexpr size_t kMaxIncludeDepth = 16;
// An included file is read whole; a scene description this big is not a scene.
constexpr std::uint64_t kMaxIncludeBytes = std::uint64_t(64) << 20;
}  // namespace

void Importer::load_includes(pugi::xml_node scene, std::vector<std::string>& chain) {
    for (pugi::xml_node inc : scene.children("include")) {
        const std::string key = "include";
        std::string written = required_attr(inc, "filename", key);
        // Relative to the main scene's folder, as Mitsuba's file resolver finds it (also for
        // files that an included file names).
        fs::path p(written);
        if (p.is_relative()) p = dir_ / p;
        std::string id = p.lexically_normal().string();
        if (std::find(chain.begin(), chain.end(), id) != chain.end())
            fail(inc, key, "'" + written + "' includes itself (through " + std::to_string(chain.size()) + " file(s))");
        if (chain.size() >= kMaxIncludeDepth)
            fail(inc, key, fmt::format("includes nest deeper than {} files", kMaxIncludeDepth));
        std::string text;
        try {
            text = gate().read(p.string(), kMaxIncludeBytes, written);
        } catch (const FileRefused& e) {
            fail(inc, key + ".filename", e.what());
        }
        // Named like the scene file itself (as given, relative to the working directory), so
        // that what the included file names resolves as it does for the scene file; a confined
        // gate (a job's files) shows it relative to its root, never by a daemon path.
        std::string shown = gate().is_confined() ? gate().shown(p.string()) : p.lexically_normal().string();
        sources_.push_back(std::make_unique<Source>(std::move(text), shown));
        Source& src = *sources_.back();
        parse_source(src);
        pugi::xml_node inner = src.doc->child("scene");
        for (pugi::xml_node d : inner.children("default"))
            warn(d, "default", "a <default> in an included file is ignored (only the scene file's count)");
        included_[inc] = inner;
        chain.push_back(id);
        load_includes(inner, chain);
        chain.pop_back();
    }
}

std::vector<pugi::xml_node> Importer::scenes() const {
    std::vector<pugi::xml_node> out;
    for (const auto& s : sources_) out.push_back(s->doc->child("scene"));
    return out;
}

void Importer::read_scene_children(pugi::xml_node scene) {
    for (pugi::xml_node c : scene.children()) {
        if (c.type() != pugi::node_element) continue;
        std::string tag = c.name();
        if (tag == "default") continue;
        if (tag == "include") {
            read_scene_children(included_.at(c));
        } else if (tag == "integrator") {
            if (have_integrator_) warn(c, "integrator", "a second integrator was ignored");
            else read_integrator(c);
            have_integrator_ = true;
        } else if (tag == "sensor") {
            if (have_sensor_) warn(c, "sensor", "a second sensor was ignored (Omega renders one camera)");
            else read_sensor(c);
            have_sensor_ = true;
        } else if (tag == "shape") {
            read_shape(c, shape_index_++);
        } else if (tag == "emitter") {
            read_emitter(c, emitter_index_++);
        } else if (tag == "bsdf" || tag == "texture") {
            // Built when a shape refers to them.
        } else {
            std::string type = c.attribute("type") ? " type=\"" + attr(c, "type", tag) + "\"" : "";
            warn(c, tag, "<" + tag + type + "> is not supported and was ignored");
        }
    }
}

SceneDesc Importer::run() {
    Source& main = *sources_.front();
    parse_source(main);
    pugi::xml_node scene = main.doc->child("scene");
    desc_.path = file_;
    std::string version = scene.attribute("version").as_string();
    if (version.empty()) warn(scene, "scene", "no version attribute; reading it as Mitsuba 3");
    else if (version[0] == '0' || version[0] == '1') {
        legacy_ = true;  // camelCase names are read as Mitsuba 3's snake_case: nothing to warn about
    }
    read_defaults(scene);
    std::vector<std::string> chain{fs::path(file_).lexically_normal().string()};
    load_includes(scene, chain);
    warn_unused_defines(scene);
    // Ids anywhere in any of the files (Mitsuba allows references to any named object).
    for (pugi::xml_node sc : scenes()) {
        for (pugi::xpath_node xn : sc.select_nodes("//*[@id and name() != 'ref']")) {
            pugi::xml_node el = xn.node();
            std::string id = attr(el, "id", el.name());
            if (ids_.count(id)) fail(el, el.name(), "duplicate id '" + id + "'");
            ids_[id] = el;
        }
    }

    read_scene_children(scene);
    if (!have_sensor_) {
        desc_.sensor.film.crop = {0, 0, desc_.sensor.film.width, desc_.sensor.film.height};
        warn(scene, "scene", "no <sensor>: using Omega's default camera");
    }
    for (pugi::xml_node sc : scenes())
        for (pugi::xml_node b : sc.children("bsdf")) {
            std::string id = b.attribute("id") ? attr(b, "id", "bsdf") : "";
            if (!referenced_ids_.count(id)) warn(b, id.empty() ? "bsdf" : "bsdf(" + id + ")", "never used by any shape");
        }
    bool any_light = !desc_.lights.empty();
    for (const ShapeDesc& s : desc_.shapes) any_light |= s.emitter.has_value() && !is_black(s.emitter->radiance);
    if (!any_light) desc_.warnings.push_back(fmt::format("{}:1: the scene has no light source; the image will be black", file_));
    desc_.files = opt_.files;
    check_scene_files(desc_);
    return std::move(desc_);
}

}  // namespace mitsuba

namespace {
using mitsuba::Importer;
namespace fs = std::filesystem;
}  // namespace

SceneDesc import_mitsuba_string(const std::string& xml, const std::string& virtual_path, const MitsubaOptions& options) {
    Importer imp(xml, virtual_path, options);
    try {
        return imp.run();
    } catch (const YAML::Exception& e) {
        throw SceneError(fmt::format("{}:1: internal error converting a value: {}", virtual_path, e.msg));
    }
}

SceneDesc import_mitsuba_file(const std::string& path, const MitsubaOptions& options) {
    std::ifstream in(path, std::ios::binary);
    std::error_code ec;
    if (!in || fs::is_directory(path, ec)) throw SceneError(fmt::format("{}: cannot open the scene file", path));
    std::stringstream ss;
    ss << in.rdbuf();
    return import_mitsuba_string(ss.str(), path, options);
}

bool is_mitsuba_path(const std::string& path) {
    std::string ext = fs::path(path).extension().string();
    for (char& c : ext) c = char(std::tolower(static_cast<unsigned char>(c)));
    return ext == ".xml";
}

SceneDesc load_scene_file(const std::string& path, const MitsubaOptions& options) {
    if (!options.camera.empty() && !is_gltf_path(path))
        throw SceneError(fmt::format("{}: --camera {}: only glTF scenes name their cameras", path, options.camera));
    if (is_mitsuba_path(path)) return import_mitsuba_file(path, options);
    if (is_gltf_path(path) && options.defines.empty()) return import_gltf_file(path, {options.camera, options.files});
    if (!options.defines.empty())
        throw SceneError(fmt::format("{}: -D {}=...: defines only apply to Mitsuba XML scenes", path,
                                     options.defines.begin()->first));
    return parse_scene_file(path);
}

}  // namespace omega