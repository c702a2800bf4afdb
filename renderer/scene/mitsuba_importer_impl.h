#pragma once
// The Mitsuba XML importer's internals, shared by its translation units:
//   mitsuba_importer.cpp  the document: defaults, integrator, sensor, transforms, shapes, emitters
//   mitsuba_bsdf.cpp      BSDFs, colours and textures
// Not part of the renderer's interface: include scene/mitsuba_importer.h instead.
#include <fmt/format.h>
#include <pugixml.hpp>
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <filesystem>
#include <map>
#include <memory>
#include <set>
#include <string>
#include <vector>

#include "io/file_gate.h"
#include "scene/mitsuba_importer.h"
#include "scene/param_bag.h"
#include "scene/scene_error.h"
#include "scene/scene_parser.h"

namespace omega::mitsuba {

namespace fs = std::filesystem;

constexpr double kPi = 3.14159265358979323846;

// Mitsuba 0.x spelled parameters in camelCase (toWorld, maxDepth, intIOR); 3.x uses snake_case.
std::string snake_case(const std::string& s);
// The numbers of a value attribute, split on commas and whitespace.
std::vector<std::string> split_numbers(const std::string& s);

// An XML element being read: which of its children were used, so the rest can be named.
struct Elem {
    pugi::xml_node node;
    std::string key;  // for messages: "shape(Floor)", "sensor.film"
    std::set<size_t> used;  // offsets of the children used
    void use(pugi::xml_node c) { used.insert(size_t(c.offset_debug())); }
};

// One XML file of the scene: the scene file itself, or one that an <include> brought in.
struct Source {
    std::string text;
    std::string file;  // as messages name it
    std::shared_ptr<const std::string> fname;
    std::vector<size_t> newlines;
    std::unique_ptr<pugi::xml_document> doc;
    Source(std::string t, std::string f)
        : text(std::move(t)), file(std::move(f)), fname(std::make_shared<const std::string>(file)),
          doc(std::make_unique<pugi::xml_document>()) {
        for (size_t i = 0; i < text.size(); ++i)
            if (text[i] == '\n') newlines.push_back(i);
    }
    int line_at(size_t offset) const {
        return int(std::upper_bound(newlines.begin(), newlines.end(), offset) - newlines.begin()) + 1;
    }
};

class Importer {
public:
    Importer(const std::string& text, const std::string& file, const MitsubaOptions& opt)
        : file_(file), opt_(opt) {
        sources_.push_back(std::make_unique<Source>(text, file));
        dir_ = fs::path(file).parent_path();
        if (dir_.empty()) dir_ = ".";
    }

    SceneDesc run();

private:
    const FileGate& gate() const { return opt_.files ? *opt_.files : *FileGate::unconfined(); }

    // ---- positions, messages: every node is named by the file it was written in.
    const Source& source_of(pugi::xml_node n) const {
        pugi::xml_node root = n.root();
        for (const auto& s : sources_)
            if (root == *s->doc) return *s;
        return *sources_.front();
    }
    const std::string& file_of(pugi::xml_node n) const { return source_of(n).file; }
    const std::shared_ptr<const std::string>& fname_of(pugi::xml_node n) const { return source_of(n).fname; }
    int line_of(pugi::xml_node n) const {
        ptrdiff_t off = n.offset_debug();
        if (off < 0) return 0;
        return source_of(n).line_at(size_t(off));
    }
    [[noreturn]] void fail(pugi::xml_node n, const std::string& key, const std::string& what) const {
        throw SceneError(fmt::format("{}:{}: {}: {}", file_of(n), line_of(n), key, what));
    }
    void warn(pugi::xml_node n, const std::string& key, const std::string& what) {
        desc_.warnings.push_back(fmt::format("{}:{}: {}: {}", file_of(n), line_of(n), key, what));
    }

    // ---- attributes and $variables
    std::string subst(const std::string& s, pugi::xml_node n, const std::string& key) const {
        std::string out;
        for (size_t i = 0; i < s.size(); ++i) {
            if (s[i] != '$') {
                out += s[i];
                continue;
            }
            size_t j = i + 1;
            while (j < s.size() && (std::isalnum(static_cast<unsigned char>(s[j])) || s[j] == '_')) ++j;
            std::string var = s.substr(i + 1, j - i - 1);
            if (var.empty()) fail(n, key, "a lone '$' in '" + s + "'");
            auto it = vars_.find(var);
            if (it == vars_.end())
                fail(n, key, "undefined variable $" + var + " (add <default name=\"" + var + "\" value=\"...\"/>)");
            out += it->second;
            i = j - 1;
        }
        return out;
    }
    std::string attr(pugi::xml_node n, const char* name, const std::string& key) const {
        return subst(n.attribute(name).as_string(), n, key);
    }
    std::string required_attr(pugi::xml_node n, const char* name, const std::string& key) const {
        if (!n.attribute(name)) fail(n, key, fmt::format("<{}> needs a '{}' attribute", n.name(), name));
        return attr(n, name, key);
    }
    std::string param_name(pugi::xml_node c, const std::string& key) const {
        std::string name = attr(c, "name", key);
        return legacy_ ? snake_case(name) : name;
    }
    std::string elem_key(pugi::xml_node n, const std::string& tag, size_t index) const {
        std::string id = n.attribute("id") ? attr(n, "id", tag) : "";
        return id.empty() ? fmt::format("{}[{}]", tag, index) : fmt::format("{}({})", tag, id);
    }

    // ---- parameters
    static bool is_value_tag(const std::string& t) {
        return t == "float" || t == "integer" || t == "boolean" || t == "string" || t == "rgb" || t == "srgb" ||
               t == "spectrum" || t == "blackbody" || t == "point" || t == "vector" || t == "transform";
    }
    // The child <tag name="name"> of e (any value tag, or a texture/ref for colours), marked used.
    pugi::xml_node find_param(Elem& e, const std::string& name) {
        for (pugi::xml_node c : e.node.children()) {
            if (c.type() != pugi::node_element || !c.attribute("name")) continue;
            if (param_name(c, e.key) == name) {
                e.use(c);
                return c;
            }
        }
        return {};
    }
    double number(pugi::xml_node c, const std::string& key) const { return to_double(attr(c, "value", key), c, key); }
    // A film size or offset: int(x) of a value past int's range is undefined, so it is refused
    // here with the file and line (the film's own checks bound it further).
    int integer(pugi::xml_node c, const std::string& key) const {
        const double v = number(c, key);
        if (!(v >= -2147483648.0 && v < 2147483648.0))
            fail(c, key, fmt::format("'{}' must be an integer within +-2^31, got {}", c.attribute("name").value(), v));
        return int(v);
    }
    // A scalar value as YAML text, checked by the section parsers later.
    YAML::Node scalar(pugi::xml_node c, const std::string& key) const {
        std::string t = c.name();
        std::string v = attr(c, "value", key);
        if (t == "boolean") {
            std::string l = v;
            for (char& ch : l) ch = char(std::tolower(static_cast<unsigned char>(ch)));
            if (l != "true" && l != "false") fail(c, key, "expected true or false, got '" + v + "'");
            return YAML::Node(l);
        }
        return YAML::Node(v);
    }
    Vec3d vec3(pugi::xml_node c, const std::string& key) const {
        if (c.attribute("value")) {
            auto parts = split_numbers(attr(c, "value", key));
            if (parts.size() == 1) parts = {parts[0], parts[0], parts[0]};
            if (parts.size() != 3) fail(c, key, "expected 3 numbers");
            Vec3d v;
            for (int i = 0; i < 3; ++i) v[i] = to_double(parts[size_t(i)], c, key);
            return v;
        }
        return {c.attribute("x") ? to_double(attr(c, "x", key), c, key) : 0.0,
                c.attribute("y") ? to_double(attr(c, "y", key), c, key) : 0.0,
                c.attribute("z") ? to_double(attr(c, "z", key), c, key) : 0.0};
    }
    double to_double(const std::string& s, pugi::xml_node c, const std::string& key) const {
        double v = 0;
        const char* b = s.data();
        if (!s.empty() && s[0] == '+') ++b;
        auto [end, ec] = std::from_chars(b, s.data() + s.size(), v);
        if (ec != std::errc() || end != s.data() + s.size() || !std::isfinite(v))
            fail(c, key, "expected a finite number, got '" + s + "'");
        return v;
    }
    static YAML::Node list3(const std::string& a, const std::string& b, const std::string& c) {
        YAML::Node n(YAML::NodeType::Sequence);
        n.push_back(a);
        n.push_back(b);
        n.push_back(c);
        return n;
    }
    static YAML::Node vec_node(const Vec3d& v) {
        return list3(fmt::format("{}", v.x), fmt::format("{}", v.y), fmt::format("{}", v.z));
    }
    // A colour parameter (<rgb>, <srgb>, <spectrum>, <float>, a bitmap <texture> or a <ref> to one)
    // as YAML: a number or [r, g, b].
    // With texture_ok (a diffuse reflectance), a bitmap becomes a v1 `{type: bitmap, ...}` mapping.
    YAML::Node colour(pugi::xml_node c, const std::string& key, bool texture_ok = false);
    Rgb texture_average(pugi::xml_node tex, const std::string& key);
    YAML::Node bitmap(pugi::xml_node tex, const std::string& key);
    YAML::Node checkerboard(pugi::xml_node tex, const std::string& key);
    // A <transform name="to_uv"> as a v1 uv transform; null (with a warning) when it mixes in z.
    YAML::Node to_uv(pugi::xml_node c, const std::string& key);

    // ---- transforms
    YAML::Node transform_ops(pugi::xml_node t, const std::string& key);
    Mat4 to_world(pugi::xml_node t, const std::string& key) {
        YAML::Node ops = transform_ops(t, key);
        if (ops.size() == 0) return Mat4{};
        return parse_to_world(ParamValue(ops, key, fname_of(t), line_of(t)));
    }

    // Runs a section parser on a YAML value built from element e, and moves the line of an error
    // about one parameter to that parameter's XML line.
    template <class F>
    auto checked(const std::string& key, pugi::xml_node n, const std::map<std::string, int>& lines, F&& f)
        -> decltype(f(std::declval<ParamValue>())) {
        try {
            return f(ParamValue(YAML::Node(), key, fname_of(n), line_of(n)));
        } catch (const SceneError& err) {
            std::string msg = err.what();
            std::string prefix = fmt::format("{}:{}: {}.", file_of(n), line_of(n), key);
            if (msg.rfind(prefix, 0) == 0) {
                std::string rest = msg.substr(prefix.size());
                size_t end = rest.find_first_of(".:[");
                auto it = lines.find(rest.substr(0, end));
                if (it != lines.end())
                    throw SceneError(fmt::format("{}:{}: {}.{}", file_of(n), it->second, key, rest));
            }
            throw;
        }
    }
    void warn_unused(Elem& e, const std::string& what = "parameter");

    // ---- sections
    void read_defaults(pugi::xml_node scene);
    void warn_unused_defines(pugi::xml_node scene);  // after the includes are read
    // Reads every file that `scene`'s <include>s name (and theirs), through the gate.
    void load_includes(pugi::xml_node scene, std::vector<std::string>& chain);
    // The children of a <scene>, an included one's in place of its <include>.
    void read_scene_children(pugi::xml_node scene);
    // Every <scene> element: the file's own and the included ones.
    std::vector<pugi::xml_node> scenes() const;
    void read_integrator(pugi::xml_node n);
    void read_sensor(pugi::xml_node n);
    YAML::Node read_bsdf(pugi::xml_node n, const std::string& key, bool two_sided, std::map<std::string, int>& lines);
    std::string material_for(pugi::xml_node bsdf, const std::string& fallback_name);
    void read_shape(pugi::xml_node n, size_t index);
    void read_emitter(pugi::xml_node n, size_t index);
    pugi::xml_node resolve_ref(pugi::xml_node ref, const std::string& key) {
        std::string id = required_attr(ref, "id", key);
        auto it = ids_.find(id);
        if (it == ids_.end()) fail(ref, key, "reference to an unknown id '" + id + "'");
        return it->second;
    }

    std::string file_;
    MitsubaOptions opt_;
    std::vector<std::unique_ptr<Source>> sources_;  // [0]: the scene file
    std::map<pugi::xml_node, pugi::xml_node> included_;  // <include> -> the <scene> it names
    fs::path dir_;
    size_t shape_index_ = 0, emitter_index_ = 0;
    bool have_integrator_ = false;
    bool legacy_ = false;  // Mitsuba 0.x parameter names
    std::map<std::string, std::string> vars_;
    std::map<std::string, pugi::xml_node> ids_;
    std::map<std::string, std::string> material_of_id_;
    std::set<std::string> referenced_ids_;
    SceneDesc desc_;
    bool have_sensor_ = false;
};

}  // namespace omega::mitsuba
