#include "scene/param_bag.h"

#include <fmt/format.h>

#include <charconv>
#include <cmath>
#include <limits>

namespace omega {

namespace {

int node_line(const YAML::Node& n, int fallback) {
    if (!n.IsDefined()) return fallback;
    YAML::Mark m = n.Mark();
    return m.line >= 0 ? m.line + 1 : fallback;
}

// Quoted scalars are strings even if they look like numbers: `fov: "45"` is a type error.
bool is_plain(const YAML::Node& n) { return n.Tag() != "!"; }

std::string printable(std::string_view s) {
    std::string out;
    for (char c : s.substr(0, 40)) out += (static_cast<unsigned char>(c) < 0x20 || c == 0x7f) ? '?' : c;
    if (s.size() > 40) out += "...";
    return out;
}

}  // namespace

// ---------------------------------------------------------------------------------------------
// ParamValue

ParamValue::ParamValue(YAML::Node node, std::string path, std::shared_ptr<const std::string> file, int fallback_line)
    : node_(std::move(node)), path_(std::move(path)), file_(std::move(file)), line_(node_line(node_, fallback_line)) {}

void ParamValue::fail(std::string_view what) const {
    if (path_.empty()) throw SceneError(fmt::format("{}:{}: {}", *file_, line_, what));
    throw SceneError(fmt::format("{}:{}: {}: {}", *file_, line_, path_, what));
}

std::string ParamValue::describe() const {
    if (is_null()) return "nothing";
    if (is_list()) return "a list";
    if (is_map()) return "a mapping";
    return "'" + printable(node_.Scalar()) + "'";
}

double ParamValue::as_double() const {
    if (!is_scalar() || !is_plain(node_)) fail("expected a number, got " + describe());
    std::string_view s = node_.Scalar();
    std::string_view body = s;
    if (!body.empty() && body[0] == '+') body.remove_prefix(1);
    // YAML spells infinities and NaN this way; from_chars would not parse them.
    std::string_view mag = (!body.empty() && body[0] == '-') ? body.substr(1) : body;
    if (mag == ".inf" || mag == ".Inf" || mag == ".INF" || mag == ".nan" || mag == ".NaN" || mag == ".NAN")
        fail("expected a finite number, got " + describe());
    double v = 0;
    auto [end, ec] = std::from_chars(body.data(), body.data() + body.size(), v);
    if (ec == std::errc::result_out_of_range) fail("number out of range: " + describe());
    if (ec != std::errc() || end != body.data() + body.size() || body.empty())
        fail("expected a number, got " + describe());
    if (!std::isfinite(v)) fail("expected a finite number, got " + describe());
    return v;
}

float ParamValue::as_float() const {
    double v = as_double();
    if (std::abs(v) > double(std::numeric_limits<float>::max())) fail("number out of range: " + describe());
    return float(v);
}

long long ParamValue::as_int(long long lo, long long hi) const {
    if (!is_scalar() || !is_plain(node_)) fail("expected an integer, got " + describe());
    std::string_view s = node_.Scalar();
    if (!s.empty() && s[0] == '+') s.remove_prefix(1);
    long long v = 0;
    auto [end, ec] = std::from_chars(s.data(), s.data() + s.size(), v);
    if (ec == std::errc::result_out_of_range) fail("integer out of range: " + describe());
    if (ec != std::errc() || end != s.data() + s.size() || s.empty())
        fail("expected an integer, got " + describe());
    if (v < lo || v > hi) fail(fmt::format("must be in [{}, {}], got {}", lo, hi, v));
    return v;
}

bool ParamValue::as_bool() const {
    if (is_scalar() && is_plain(node_)) {
        const std::string& s = node_.Scalar();
        for (const char* t : {"true", "True", "TRUE", "yes", "Yes", "YES", "on", "On", "ON"})
            if (s == t) return true;
        for (const char* f : {"false", "False", "FALSE", "no", "No", "NO", "off", "Off", "OFF"})
            if (s == f) return false;
    }
    fail("expected true or false, got " + describe());
}

std::string ParamValue::as_string() const {
    if (!is_scalar()) fail("expected a string, got " + describe());
    return node_.Scalar();
}

Rgb ParamValue::as_rgb() const {
    if (is_scalar()) {
        float v = as_float();
        return {v, v, v};
    }
    if (!is_list() || node_.size() != 3) fail("expected [r, g, b] or a single number, got " + describe());
    auto items = as_list();
    return {items[0].as_float(), items[1].as_float(), items[2].as_float()};
}

Vec3d ParamValue::as_vec3() const {
    if (!is_list() || node_.size() != 3) fail("expected [x, y, z], got " + describe());
    auto items = as_list();
    Vec3d v{items[0].as_double(), items[1].as_double(), items[2].as_double()};
    return v;
}

ParamValue ParamValue::child(YAML::Node n, const std::string& suffix, int fallback_line) const {
    return ParamValue(std::move(n), path_ + suffix, file_, fallback_line);
}

std::vector<ParamValue> ParamValue::as_list() const {
    if (!is_list()) fail("expected a list, got " + describe());
    std::vector<ParamValue> out;
    size_t i = 0;
    for (auto it = node_.begin(); it != node_.end(); ++it, ++i)
        out.push_back(child(*it, fmt::format("[{}]", i), line_));
    return out;
}

ParamBag ParamValue::as_bag() const { return ParamBag(*this); }

// ---------------------------------------------------------------------------------------------
// ParamBag

ParamBag::ParamBag(const ParamValue& map) : self_(map), entries_(std::make_shared<std::vector<Entry>>()) {
    if (!map.is_map()) map.fail("expected a mapping, got " + map.describe());
    for (auto it = map.node().begin(); it != map.node().end(); ++it) {
        // By value: it-> yields a proxy, and a reference into it would dangle.
        YAML::Node k = it->first;
        YAML::Node value = it->second;
        int kline = node_line(k, map.line());
        std::string key_path = map.path();
        if (!k.IsScalar()) {
            if (key_path.empty()) throw SceneError(fmt::format("{}:{}: keys must be plain strings", map.file(), kline));
            throw SceneError(fmt::format("{}:{}: {}: keys must be plain strings", map.file(), kline, key_path));
        }
        const std::string& key = k.Scalar();
        std::string child_path = key_path.empty() ? key : key_path + "." + key;
        for (const Entry& e : *entries_)
            if (e.key == key)
                throw SceneError(fmt::format("{}:{}: {}: duplicate key", map.file(), kline, child_path));
        entries_->push_back({key, kline, value, false});
    }
}

bool ParamBag::has(const std::string& key) const {
    for (const Entry& e : *entries_)
        if (e.key == key) return true;
    return false;
}

std::vector<std::string> ParamBag::keys() const {
    std::vector<std::string> out;
    for (const Entry& e : *entries_) out.push_back(e.key);
    return out;
}

std::optional<ParamValue> ParamBag::get(const std::string& key) {
    for (Entry& e : *entries_)
        if (e.key == key) {
            e.used = true;
            return self_.child(e.value, self_.path().empty() ? key : "." + key, e.key_line);
        }
    return std::nullopt;
}

ParamValue ParamBag::require(const std::string& key) {
    if (auto v = get(key)) return *v;
    std::string path = self_.path().empty() ? key : self_.path() + "." + key;
    throw SceneError(fmt::format("{}:{}: {}: missing key", self_.file(), self_.line(), path));
}

double ParamBag::get_double(const std::string& key, double def) {
    auto v = get(key);
    return v ? v->as_double() : def;
}
float ParamBag::get_float(const std::string& key, float def) {
    auto v = get(key);
    return v ? v->as_float() : def;
}
int ParamBag::get_int(const std::string& key, int def, int lo, int hi) {
    auto v = get(key);
    return v ? int(v->as_int(lo, hi)) : def;
}
bool ParamBag::get_bool(const std::string& key, bool def) {
    auto v = get(key);
    return v ? v->as_bool() : def;
}
std::string ParamBag::get_string(const std::string& key, const std::string& def) {
    auto v = get(key);
    return v ? v->as_string() : def;
}
Rgb ParamBag::get_rgb(const std::string& key, Rgb def) {
    auto v = get(key);
    return v ? v->as_rgb() : def;
}
Vec3d ParamBag::get_vec3(const std::string& key, Vec3d def) {
    auto v = get(key);
    return v ? v->as_vec3() : def;
}

ParamBag ParamBag::bag(const std::string& key) { return require(key).as_bag(); }

std::optional<ParamBag> ParamBag::opt_bag(const std::string& key) {
    auto v = get(key);
    if (!v) return std::nullopt;
    return v->as_bag();
}

std::vector<ParamValue> ParamBag::list(const std::string& key) {
    auto v = get(key);
    if (!v) return {};
    return v->as_list();
}

std::vector<std::string> ParamBag::unused_messages() const {
    std::vector<std::string> out;
    for (const Entry& e : *entries_)
        if (!e.used) {
            std::string path = self_.path().empty() ? e.key : self_.path() + "." + e.key;
            out.push_back(fmt::format("{}:{}: {}: unknown key", self_.file(), e.key_line, path));
        }
    return out;
}

void ParamBag::check_unused() const {
    auto msgs = unused_messages();
    if (msgs.empty()) return;
    std::string all = msgs[0];
    for (size_t i = 1; i < msgs.size(); ++i) all += "\n" + msgs[i];
    throw SceneError(all);
}

}  // namespace omega
