#pragma once
// The job page's WebSocket messages (docs/web.md): what the browser sends to `omega view`
// (JSON text, decoded here with the protocol's hardened YAML reader, since JSON is YAML 1.2),
// what `omega view` sends back (JSON text in the canonical one-line form of the protocol's
// HeaderWriter), and the binary messages that carry float pixels and EXR files.
//
// No I/O and no threads: pure functions, callable from any thread without a lock. Fuzzed by
// fuzz/fuzz_view_messages.cpp.
#include <cstdint>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "protocol/errors.h"
#include "protocol/messages.h"
#include "protocol/result.h"

namespace omega::client {

// The largest text message the page may send (a login with a long token is far below it).
inline constexpr std::size_t kMaxViewCommandBytes = 4096;

enum class ViewCommandKind { login, list, open, close, cancel, pause, resume, set_priority, fetch };
std::string_view to_string(ViewCommandKind k);

// One message from the page: {"type": T, "id": N, ...}. `id` (u64, chosen by the page) is echoed
// by the reply. login: user, token (printable strings, at most 1024 bytes); list, close: nothing more; open,
// cancel, pause, resume, fetch: job (u64); set_priority: job, priority (i64 in [-1000, 1000]).
struct ViewCommand {
    ViewCommandKind kind = ViewCommandKind::list;
    std::uint64_t id = 0;
    std::uint64_t job = 0;
    std::int64_t priority = 0;
    std::string user, token;
};

// Decodes one text message. Never throws: anything malformed (not UTF-8, not a JSON/YAML
// mapping, unknown type, a field missing, of the wrong type or out of range, over
// kMaxViewCommandBytes) is a DecodeError whose message names the field.
protocol::Result<ViewCommand, protocol::DecodeError> decode_view_command(std::string_view text);
// The canonical JSON of a command (the login's token included); decode(encode(c)) == c.
std::string encode_view_command(const ViewCommand& c);

// ---- the WebSocket upgrade request ----
// True for 127.0.0.0/8, ::1 and "localhost" (the only hosts `omega view --listen` accepts).
bool is_loopback_host(std::string_view host);
// Whether to accept a WebSocket upgrade with these Host and Origin headers (null: absent): the
// Host must name a loopback host (no DNS rebinding), and the Origin, when the browser sends one,
// must be "http://" + Host, the page itself (no cross-site WebSocket hijacking).
bool websocket_upgrade_allowed(const char* host, const char* origin);

// ---- replies and events, JSON text (one line) ----
// {"type": "welcome", "id", "user", "server", "auth"}
std::string view_welcome(std::uint64_t id, std::string_view user, std::string_view server, std::string_view auth);
// {"type": "error", "id", "code", "message"}: code is a protocol error code or `bad_request`.
std::string view_error(std::uint64_t id, std::string_view code, std::string_view message);
// {"type": "ok", "id", "request", "job"}
std::string view_ok(std::uint64_t id, ViewCommandKind request, std::uint64_t job);
// {"type": "jobs", "id", "user", "jobs": [job fields as in the protocol, plus "label" (the
// name `omega list` prints in its NAME column), "progress_text" (its PROGRESS column) and "mine"
// (1 when owned by user, else 0)]}
std::string view_jobs(std::uint64_t id, std::string_view user, const std::vector<protocol::JobInfo>& jobs);
// {"type": "job", "id", job fields..., "label", "mine"}: the job an `open` showed.
std::string view_job(std::uint64_t id, std::string_view user, const protocol::JobInfo& info);
// {"type": "progress", "id", "job", "state", "progress": {...}}
std::string view_progress(std::uint64_t id, std::uint64_t job, protocol::JobState state, const protocol::ProgressInfo& p);
// {"type": "done", "id", "job", "state", "progress", "message"?}
std::string view_done(std::uint64_t id, const protocol::Done& d);
// {"type": "warnings", "id", "job", "warnings": [strings], "nonfinite": u64}
std::string view_warnings(std::uint64_t id, std::uint64_t job, const std::vector<std::string>& warnings,
                          std::uint64_t nonfinite);

// ---- binary messages (little-endian) ----
// Tile: 48-byte header, then width*height*3 float32 RGB, then as many float32 variances.
//   0 "OTF1" | 4 u32 flags (bit 0: variance present) | 8 u64 job | 16 u32 x0 | 20 u32 y0
//   24 u32 x1 | 28 u32 y1 | 32 u32 film width | 36 u32 film height | 40 u32 pass | 44 u32 spp
// Non-finite values are written as 0 (the page never sees a NaN).
inline constexpr std::size_t kTileHeaderBytes = 48;
struct FloatTile {
    std::uint64_t job = 0;
    std::uint32_t x0 = 0, y0 = 0, x1 = 0, y1 = 0;
    std::uint32_t film_width = 0, film_height = 0;
    std::uint32_t pass = 0, spp = 0;
    std::span<const float> rgb;  // (x1-x0)*(y1-y0)*3
    std::span<const float> var;  // the same size, or empty
};
// Throws std::invalid_argument when the spans do not match the rect.
std::string pack_float_tile(const FloatTile& t);
// EXR file: 16-byte header "OEXR" | u32 0 | u64 job, then the EXR file's bytes.
std::string pack_exr(std::uint64_t job, std::string_view exr);

}  // namespace omega::client
