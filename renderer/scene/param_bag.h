#pragma once
// A Mitsuba-style parameter bag over a YAML mapping. Every getter marks its key as read, so that
// check_unused() can reject typos instead of silently rendering something else. Every error is a
// SceneError "file:line: dotted.key: what is wrong".
#include <yaml-cpp/yaml.h>

#include <climits>
#include <initializer_list>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "math/vec.h"
#include "scene/scene_desc.h"
#include "scene/scene_error.h"

namespace omega {

class ParamBag;

// One YAML value together with the key path and line that errors about it should name.
class ParamValue {
public:
    ParamValue(YAML::Node node, std::string path, std::shared_ptr<const std::string> file, int fallback_line);

    const YAML::Node& node() const { return node_; }
    const std::string& path() const { return path_; }
    const std::string& file() const { return *file_; }
    int line() const { return line_; }
    SourceLoc loc() const { return {*file_, line_, path_}; }

    [[noreturn]] void fail(std::string_view what) const;

    bool is_null() const { return !node_.IsDefined() || node_.IsNull(); }
    bool is_scalar() const { return node_.IsDefined() && node_.IsScalar(); }
    bool is_map() const { return node_.IsDefined() && node_.IsMap(); }
    bool is_list() const { return node_.IsDefined() && node_.IsSequence(); }
    // How the value looks in a message: 'abc', a list, a mapping, nothing.
    std::string describe() const;

    double as_double() const;  // finite
    float as_float() const;    // finite and representable as float
    long long as_int(long long lo = LLONG_MIN, long long hi = LLONG_MAX) const;
    bool as_bool() const;
    std::string as_string() const;
    Rgb as_rgb() const;  // [r, g, b] or a single number for grey
    Vec3d as_vec3() const;
    std::vector<ParamValue> as_list() const;
    ParamBag as_bag() const;

    // A child of this value at `suffix` (".key" or "[i]") for error messages.
    ParamValue child(YAML::Node n, const std::string& suffix, int fallback_line) const;

private:
    YAML::Node node_;
    std::string path_;
    std::shared_ptr<const std::string> file_;
    int line_;
};

class ParamBag {
public:
    explicit ParamBag(const ParamValue& map);  // fails unless the value is a mapping

    const ParamValue& self() const { return self_; }
    [[noreturn]] void fail(std::string_view what) const { self_.fail(what); }

    bool has(const std::string& key) const;  // does not count as reading the key
    std::vector<std::string> keys() const;   // in file order; does not count as reading
    std::optional<ParamValue> get(const std::string& key);  // marks the key as read
    ParamValue require(const std::string& key);             // fails "missing key" if absent

    double get_double(const std::string& key, double def);
    float get_float(const std::string& key, float def);
    int get_int(const std::string& key, int def, int lo = INT_MIN, int hi = INT_MAX);
    bool get_bool(const std::string& key, bool def);
    std::string get_string(const std::string& key, const std::string& def);
    Rgb get_rgb(const std::string& key, Rgb def);
    Vec3d get_vec3(const std::string& key, Vec3d def);

    template <class E>
    E get_enum(const std::string& key, std::initializer_list<std::pair<std::string_view, E>> allowed, E def) {
        auto v = get(key);
        return v ? enum_value(*v, allowed) : def;
    }
    template <class E>
    static E enum_value(const ParamValue& v, std::initializer_list<std::pair<std::string_view, E>> allowed) {
        std::string s = v.is_scalar() ? v.node().Scalar() : std::string();
        for (auto& [name, e] : allowed)
            if (v.is_scalar() && s == name) return e;
        std::string list;
        for (auto& [name, e] : allowed) list += (list.empty() ? "" : ", ") + std::string(name);
        v.fail("expected one of " + list + ", got " + v.describe());
    }

    ParamBag bag(const std::string& key);  // required nested mapping
    std::optional<ParamBag> opt_bag(const std::string& key);
    std::vector<ParamValue> list(const std::string& key);  // absent = empty

    // One "file:line: key: unknown key" per key never read, in file order.
    std::vector<std::string> unused_messages() const;
    // Throws a SceneError listing every unread key (one per line) if there is any.
    void check_unused() const;

private:
    struct Entry {
        std::string key;
        int key_line;
        YAML::Node value;
        bool used = false;
    };
    ParamValue self_;
    std::shared_ptr<std::vector<Entry>> entries_;  // shared so copies of a bag see the same reads
};

}  // namespace omega
