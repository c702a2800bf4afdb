#include "view_messages.h"

#include <arpa/inet.h>
#include <yaml-cpp/yaml.h>

#include <cmath>
#include <cstring>
#include <set>
#include <stdexcept>

#include "protocol/header.h"
#include "protocol/header_writer.h"
#include "remote_common.h"

namespace omega::client {

namespace proto = omega::protocol;
using proto::DecodeError;
using proto::HeaderWriter;

namespace {

constexpr std::size_t kMaxCredentialBytes = 1024;

struct KindName {
    ViewCommandKind kind;
    const char* name;
};
constexpr KindName kKinds[] = {
    {ViewCommandKind::login, "login"},   {ViewCommandKind::list, "list"},   {ViewCommandKind::open, "open"},
    {ViewCommandKind::close, "close"},   {ViewCommandKind::cancel, "cancel"}, {ViewCommandKind::pause, "pause"},
    {ViewCommandKind::resume, "resume"}, {ViewCommandKind::set_priority, "set_priority"},
    {ViewCommandKind::fetch, "fetch"},
};

// User names and tokens are printable text: no C0 control character or DEL, and none of the
// code points YAML folds as line breaks (U+0085, U+2028, U+2029) or drops (U+FEFF), so that
// the canonical JSON of a command reads back as the same command (fuzz_view_messages found a
// NEL turned into a space).
bool printable(std::string_view s) {
    for (std::size_t i = 0; i < s.size(); ++i) {
        const auto c = static_cast<unsigned char>(s[i]);
        if (c < 0x20 || c == 0x7f) return false;
        if (c == 0xc2 && i + 1 < s.size() && static_cast<unsigned char>(s[i + 1]) == 0x85) return false;
        if (c == 0xe2 && s.substr(i, 3) >= "\xe2\x80\xa8" && s.substr(i, 3) <= "\xe2\x80\xa9") return false;
        if (s.substr(i, 3) == "\xef\xbb\xbf") return false;
    }
    return true;
}

bool takes_job(ViewCommandKind k) {
    return k != ViewCommandKind::login && k != ViewCommandKind::list && k != ViewCommandKind::close;
}

// The NAME column of `omega list` is the job's name as submitted.
std::string label_of(const proto::JobInfo& j) { return j.name; }

void write_halt(HeaderWriter& w, const proto::Halt& h) {
    w.key("halt").begin_map();
    if (h.spp) w.field_u("spp", *h.spp);
    if (h.time_s) w.field_f("time_s", *h.time_s);
    if (h.target_error) w.field_f("target_error", *h.target_error);
    w.end_map();
}

void write_progress(HeaderWriter& w, const proto::ProgressInfo& p) {
    w.key("progress").begin_map();
    w.field_u("pass", p.pass).field_u("spp", p.spp).field_f("elapsed_s", p.elapsed_s);
    if (p.rel_error) w.field_f("rel_error", *p.rel_error);
    w.field_f("samples_per_s", p.samples_per_s);
    w.end_map();
}

void write_job_fields(HeaderWriter& w, std::string_view user, const proto::JobInfo& j) {
    w.field_u("job", j.job).field("name", j.name).field("state", proto::to_string(j.state));
    w.field_i("priority", j.priority).field("owner", j.owner);
    write_halt(w, j.halt);
    write_progress(w, j.progress);
    w.field("label", label_of(j)).field("progress_text", format_progress(j.progress, j.halt));
    w.field_u("mine", j.owner == user ? 1 : 0);
}

void put_u32(std::string& out, std::size_t at, std::uint32_t v) {
    for (int i = 0; i < 4; ++i) out[at + std::size_t(i)] = char((v >> (8 * i)) & 0xff);
}
void put_u64(std::string& out, std::size_t at, std::uint64_t v) {
    for (int i = 0; i < 8; ++i) out[at + std::size_t(i)] = char((v >> (8 * i)) & 0xff);
}
void put_floats(std::string& out, std::size_t at, std::span<const float> v) {
    for (std::size_t i = 0; i < v.size(); ++i) {
        const float f = std::isfinite(v[i]) ? v[i] : 0.f;
        std::uint32_t bits;
        std::memcpy(&bits, &f, 4);
        put_u32(out, at + 4 * i, bits);
    }
}

}  // namespace

std::string_view to_string(ViewCommandKind k) {
    for (const auto& e : kKinds)
        if (e.kind == k) return e.name;
    return "?";
}

proto::Result<ViewCommand, DecodeError> decode_view_command(std::string_view text) {
    if (text.size() > kMaxViewCommandBytes)
        return proto::fail(DecodeError::out_of_range, "message: over " + std::to_string(kMaxViewCommandBytes) + " bytes");
    if (!proto::is_valid_utf8(text)) return proto::fail(DecodeError::invalid_value, "message: not valid UTF-8");
    // JSON allows no raw control character (JSON.stringify escapes them); yaml-cpp, which reads
    // it, would take a NUL for the end of its input and hand back a broken scalar.
    for (char ch : text)
        if (static_cast<unsigned char>(ch) < 0x20 && ch != '\t' && ch != '\n' && ch != '\r')
            return proto::fail(DecodeError::invalid_value, "message: a raw control character (JSON escapes them)");
    YAML::Node root;
    try {
        root.reset(YAML::Load(std::string(text)));
    } catch (const std::exception& e) {
        return proto::fail(DecodeError::invalid_value, std::string("message: not JSON: ") + e.what());
    }
    if (!root.IsMap()) return proto::fail(DecodeError::wrong_type, "message: not a JSON object");
    std::set<std::string> keys;
    for (const auto& kv : root) {
        if (!kv.first.IsScalar()) return proto::fail(DecodeError::wrong_type, "message: a key is not a string");
        if (!keys.insert(kv.first.Scalar()).second)
            return proto::fail(DecodeError::invalid_value, "message: repeats the key '" + kv.first.Scalar().substr(0, 64) + "'");
    }
    proto::FieldReader r(root);
    const std::string type = r.str("type", 64);
    ViewCommand c;
    c.id = r.u64("id");
    if (!r.ok()) return r.failure();
    bool known = false;
    for (const auto& e : kKinds)
        if (type == e.name) {
            c.kind = e.kind;
            known = true;
        }
    if (!known) return proto::fail(DecodeError::invalid_value, "type: unknown message type '" + type + "'");
    if (takes_job(c.kind)) c.job = r.u64("job");
    if (c.kind == ViewCommandKind::set_priority) c.priority = r.i64("priority", proto::kMinPriority, proto::kMaxPriority);
    if (c.kind == ViewCommandKind::login) {
        c.user = r.str("user", kMaxCredentialBytes);
        c.token = r.str("token", kMaxCredentialBytes);
        if (r.ok() && !(printable(c.user) && proto::is_valid_utf8(c.user)))
            r.fail(DecodeError::invalid_value, "user", "not printable text");
        if (r.ok() && !(printable(c.token) && proto::is_valid_utf8(c.token)))
            r.fail(DecodeError::invalid_value, "token", "not printable text");
    }
    if (!r.ok()) return r.failure();
    return c;
}

std::string encode_view_command(const ViewCommand& c) {
    HeaderWriter w;
    w.begin_map().field("type", to_string(c.kind)).field_u("id", c.id);
    if (takes_job(c.kind)) w.field_u("job", c.job);
    if (c.kind == ViewCommandKind::set_priority) w.field_i("priority", c.priority);
    if (c.kind == ViewCommandKind::login) w.field("user", c.user).field("token", c.token);
    return w.end_map().take();
}

std::string view_welcome(std::uint64_t id, std::string_view user, std::string_view server, std::string_view auth) {
    HeaderWriter w;
    w.begin_map().field("type", "welcome").field_u("id", id).field("user", user).field("server", server);
    return w.field("auth", auth).end_map().take();
}

std::string view_error(std::uint64_t id, std::string_view code, std::string_view message) {
    HeaderWriter w;
    w.begin_map().field("type", "error").field_u("id", id).field("code", code).field("message", message);
    return w.end_map().take();
}

std::string view_ok(std::uint64_t id, ViewCommandKind request, std::uint64_t job) {
    HeaderWriter w;
    w.begin_map().field("type", "ok").field_u("id", id).field("request", to_string(request)).field_u("job", job);
    return w.end_map().take();
}

std::string view_jobs(std::uint64_t id, std::string_view user, const std::vector<proto::JobInfo>& jobs) {
    HeaderWriter w;
    w.begin_map().field("type", "jobs").field_u("id", id).field("user", user).key("jobs").begin_list();
    for (const auto& j : jobs) {
        w.begin_map();
        write_job_fields(w, user, j);
        w.end_map();
    }
    return w.end_list().end_map().take();
}

std::string view_job(std::uint64_t id, std::string_view user, const proto::JobInfo& info) {
    HeaderWriter w;
    w.begin_map().field("type", "job").field_u("id", id);
    write_job_fields(w, user, info);
    return w.end_map().take();
}

std::string view_progress(std::uint64_t id, std::uint64_t job, proto::JobState state, const proto::ProgressInfo& p) {
    HeaderWriter w;
    w.begin_map().field("type", "progress").field_u("id", id).field_u("job", job).field("state", proto::to_string(state));
    write_progress(w, p);
    return w.end_map().take();
}

std::string view_done(std::uint64_t id, const proto::Done& d) {
    HeaderWriter w;
    w.begin_map().field("type", "done").field_u("id", id).field_u("job", d.job).field("state", proto::to_string(d.state));
    write_progress(w, d.progress);
    if (d.message) w.field("message", *d.message);
    return w.end_map().take();
}

std::string view_warnings(std::uint64_t id, std::uint64_t job, const std::vector<std::string>& warnings,
                          std::uint64_t nonfinite) {
    HeaderWriter w;
    w.begin_map().field("type", "warnings").field_u("id", id).field_u("job", job).key("warnings").begin_list();
    for (const auto& s : warnings) w.str(s);
    return w.end_list().field_u("nonfinite", nonfinite).end_map().take();
}

bool is_loopback_host(std::string_view host) {
    if (host == "localhost" || host == "::1") return true;
    if (host.size() > 15) return false;
    const std::string h(host);
    in_addr a{};
    return inet_pton(AF_INET, h.c_str(), &a) == 1 && (ntohl(a.s_addr) >> 24) == 127;
}

namespace {
// A Host header's port: 1-5 digits, at most 65535 (RFC 7230 allows digits only).
bool valid_port(std::string_view p) {
    if (p.empty() || p.size() > 5) return false;
    unsigned v = 0;
    for (char c : p) {
        if (c < '0' || c > '9') return false;
        v = v * 10 + unsigned(c - '0');
    }
    return v <= 65535;
}
}  // namespace

bool websocket_upgrade_allowed(const char* host, const char* origin) {
    if (!host) return false;
    const std::string_view h(host);
    // "[v6]:port", "[v6]", "name:port" or "name"; brackets hold only an IPv6 literal, so
    // "[localhost]" or "[127.0.0.1]" (which no browser sends) are refused, as is any port that is
    // not a number: the check accepts what a browser at the page's own address sends, nothing else.
    std::string_view name, rest;
    if (!h.empty() && h.front() == '[') {
        const auto e = h.find(']');
        if (e == std::string_view::npos) return false;
        name = h.substr(1, e - 1);
        rest = h.substr(e + 1);
        if (name != "::1") return false;
    } else {
        const auto c = h.find(':');
        name = h.substr(0, c);
        rest = c == std::string_view::npos ? std::string_view() : h.substr(c);
        if (name == "::1" || !is_loopback_host(name)) return false;
    }
    if (!rest.empty() && (rest.front() != ':' || !valid_port(rest.substr(1)))) return false;
    return !origin || std::string_view(origin) == "http://" + std::string(h);
}

std::string pack_float_tile(const FloatTile& t) {
    if (t.x1 <= t.x0 || t.y1 <= t.y0 || t.x1 > t.film_width || t.y1 > t.film_height)
        throw std::invalid_argument("float tile: bad rect");
    const std::size_t n = std::size_t(t.x1 - t.x0) * std::size_t(t.y1 - t.y0) * 3;
    if (t.rgb.size() != n || (!t.var.empty() && t.var.size() != n))
        throw std::invalid_argument("float tile: buffers do not match the rect");
    std::string out(kTileHeaderBytes + 4 * (t.rgb.size() + t.var.size()), '\0');
    std::memcpy(out.data(), "OTF1", 4);
    put_u32(out, 4, t.var.empty() ? 0u : 1u);
    put_u64(out, 8, t.job);
    put_u32(out, 16, t.x0);
    put_u32(out, 20, t.y0);
    put_u32(out, 24, t.x1);
    put_u32(out, 28, t.y1);
    put_u32(out, 32, t.film_width);
    put_u32(out, 36, t.film_height);
    put_u32(out, 40, t.pass);
    put_u32(out, 44, t.spp);
    put_floats(out, kTileHeaderBytes, t.rgb);
    put_floats(out, kTileHeaderBytes + 4 * t.rgb.size(), t.var);
    return out;
}

std::string pack_exr(std::uint64_t job, std::string_view exr) {
    std::string out(16, '\0');
    std::memcpy(out.data(), "OEXR", 4);
    put_u64(out, 8, job);
    out.append(exr);
    return out;
}

}  // namespace omega::client
