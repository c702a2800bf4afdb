#pragma once
// Typed messages. encode() gives a Frame in canonical form; decode<T>() checks every field's
// type and range and returns a named DecodeError rather than throwing. docs/protocol.md lists
// each message's fields in the order encode() writes them.
#include <cstdint>
#include <optional>
#include <string>
#include <variant>
#include <vector>

#include "protocol/errors.h"
#include "protocol/frame.h"
#include "protocol/header.h"
#include "protocol/message_type.h"
#include "protocol/result.h"

namespace omega::protocol {

// Version 1 is the first. A peer speaks every version in [min_version, version].
inline constexpr std::uint32_t kProtocolVersion = 1;
inline constexpr std::uint32_t kMinProtocolVersion = 1;

// The highest version both sides speak, or nothing (the daemon then answers
// `error unsupported_version` and closes).
std::optional<std::uint32_t> negotiate_version(std::uint32_t client_min, std::uint32_t client_max,
                                               std::uint32_t server_min = kMinProtocolVersion,
                                               std::uint32_t server_max = kProtocolVersion);

// Field limits shared by the decoders and docs/protocol.md.
inline constexpr std::size_t kMaxNameBytes = 4096;
inline constexpr std::size_t kMaxMessageBytes = 65536;
inline constexpr std::size_t kMaxAssets = 10000;
inline constexpr std::size_t kMaxJobsListed = 100000;
inline constexpr std::int64_t kMinPriority = -1000;
inline constexpr std::int64_t kMaxPriority = 1000;
inline constexpr std::size_t kNonceBytes = 32;
inline constexpr std::uint64_t kMaxWorkers = 100000;  // a job's `workers`, and workers listed in job_info
inline constexpr std::uint64_t kMaxWorkerThreads = 4096;

enum class AuthMethod { none, peer, hmac_sha256 };
enum class JobState { queued, running, paused, done, failed, cancelled };
std::string_view to_string(AuthMethod a);
std::string_view to_string(JobState s);
// done, failed or cancelled: a job in one of these states never runs again.
constexpr bool is_terminal(JobState s) { return s == JobState::done || s == JobState::failed || s == JobState::cancelled; }

bool is_sha256_hex(std::string_view s);  // 64 lowercase hex digits
bool is_lower_hex(std::string_view s);
// The bytes the client signs in the TCP handshake: HMAC-SHA256(token, auth_signed_text(...)).
std::string auth_signed_text(std::string_view nonce_hex, std::string_view user);

// ---- session ----
struct Hello {
  std::uint64_t id = 0;
  std::uint32_t version = kProtocolVersion;
  std::uint32_t min_version = kMinProtocolVersion;
  std::string client;  // free text, e.g. "omega/0.1"
  bool operator==(const Hello&) const = default;
};
struct Welcome {
  std::uint64_t id = 0;
  std::uint32_t version = kProtocolVersion;  // the negotiated version
  std::string server;
  AuthMethod auth = AuthMethod::none;
  std::optional<std::string> nonce;  // 64 hex digits; present exactly when auth is hmac_sha256
  std::optional<std::string> user;   // who the daemon already knows the peer to be (peer auth)
  bool operator==(const Welcome&) const = default;
};
struct Auth {
  std::uint64_t id = 0;
  std::string user;
  std::string mac;  // 64 hex digits
  bool operator==(const Auth&) const = default;
};
struct Ok {
  std::uint64_t id = 0;
  bool operator==(const Ok&) const = default;
};
struct Error {
  std::uint64_t id = 0;
  ErrorCode code = ErrorCode::internal;
  std::string message;  // for scene_invalid: the parser's "file:line: key: what" lines
  bool operator==(const Error&) const = default;
};
struct Ping {
  std::uint64_t id = 0;
  bool operator==(const Ping&) const = default;
};
struct Pong {
  std::uint64_t id = 0;
  bool operator==(const Pong&) const = default;
};
struct Bye {
  std::uint64_t id = 0;
  bool operator==(const Bye&) const = default;
};

// ---- jobs ----
struct Halt {
  std::optional<std::uint64_t> spp;
  std::optional<double> time_s;
  std::optional<double> target_error;
  bool operator==(const Halt&) const = default;
};
struct AssetRef {
  std::string name;  // the path the scene uses, relative, no ".." component
  std::string sha256;
  std::uint64_t size = 0;
  bool operator==(const AssetRef&) const = default;
};
struct Submit {
  std::uint64_t id = 0;
  std::string name;  // scene name, used for default output names; may be empty
  std::int64_t priority = 0;
  Halt halt;  // empty: the scene's own spp/time/target_error
  std::uint64_t seed = 0;
  std::optional<std::string> integrator;
  std::optional<std::string> sampler;  // "sobol" | "independent": overrides the scene's
  std::vector<AssetRef> assets;
  std::string scene;  // payload: the scene YAML
  // Render on connected `omega worker`s instead of the daemon's own threads (docs/farm.md):
  // > 0: the workers omegad starts (executor slurm); absent: the daemon's default (config `workers`).
  std::optional<std::uint32_t> workers;
  std::optional<std::uint64_t> unit_spp;  // samples per work unit; absent: sized to ~unit_seconds
  bool operator==(const Submit&) const = default;
};
struct NeedAssets {
  std::uint64_t id = 0;  // echoes the submit
  std::vector<std::string> missing;  // sha256 hex of each asset the daemon lacks
  bool operator==(const NeedAssets&) const = default;
};
struct Asset {
  std::uint64_t id = 0;  // echoes the submit it belongs to
  std::string sha256;
  std::string data;  // payload
  bool operator==(const Asset&) const = default;
};
struct Accepted {
  std::uint64_t id = 0;
  std::uint64_t job = 0;
  bool operator==(const Accepted&) const = default;
};
struct ProgressInfo {
  std::uint64_t pass = 0;
  std::uint64_t spp = 0;
  double elapsed_s = 0;
  std::optional<double> rel_error;  // absent until it can be estimated
  double samples_per_s = 0;
  bool operator==(const ProgressInfo&) const = default;
};
// One `omega worker` session that holds or held units of a job (job_info of a worker job).
struct WorkerInfo {
  std::string name;               // the worker's own name (host:pid), then its connection
  std::uint64_t units_done = 0;   // units of this job it finished in this session
  std::vector<std::string> units; // the ranges it renders now, "A:B"
  double samples_per_s = 0;       // pixel samples per second of its last unit
  bool operator==(const WorkerInfo&) const = default;
};
struct JobInfo {
  std::uint64_t job = 0;
  std::string name;
  JobState state = JobState::queued;
  std::int64_t priority = 0;
  std::string owner;
  Halt halt;
  ProgressInfo progress;
  std::vector<WorkerInfo> workers;  // a worker job's workers; absent (empty) for local jobs
  bool operator==(const JobInfo&) const = default;
};
struct Status {
  std::uint64_t id = 0;
  std::uint64_t job = 0;
  bool operator==(const Status&) const = default;
};
struct JobInfoReply {
  std::uint64_t id = 0;
  JobInfo info;
  bool operator==(const JobInfoReply&) const = default;
};
struct List {
  std::uint64_t id = 0;
  bool operator==(const List&) const = default;
};
struct JobList {
  std::uint64_t id = 0;
  std::vector<JobInfo> jobs;
  bool operator==(const JobList&) const = default;
};
// cancel / pause / resume / delete / subscribe / unsubscribe / fetch share one shape.
template <MessageType T>
struct JobRequest {
  static constexpr MessageType kType = T;
  std::uint64_t id = 0;
  std::uint64_t job = 0;
  bool operator==(const JobRequest&) const = default;
};
using Cancel = JobRequest<MessageType::cancel>;
using Pause = JobRequest<MessageType::pause>;
using Resume = JobRequest<MessageType::resume>;
using Delete = JobRequest<MessageType::delete_job>;
using Subscribe = JobRequest<MessageType::subscribe>;
using Unsubscribe = JobRequest<MessageType::unsubscribe>;
using Fetch = JobRequest<MessageType::fetch>;
struct SetPriority {
  std::uint64_t id = 0;
  std::uint64_t job = 0;
  std::int64_t priority = 0;
  bool operator==(const SetPriority&) const = default;
};

// ---- streams (replies to subscribe / fetch) ----
struct Rect {
  std::uint32_t x0 = 0, y0 = 0, x1 = 0, y1 = 0;  // half-open: [x0, x1) x [y0, y1)
  bool operator==(const Rect&) const = default;
};
struct Tile {
  std::uint64_t id = 0;  // echoes the subscribe
  std::uint64_t job = 0;
  Rect rect;
  std::uint64_t pass = 0;
  std::uint64_t spp = 0;
  std::uint64_t version = 0;  // grows with every update of this rect; newer replaces older
  std::string exr;            // payload
  bool operator==(const Tile&) const = default;
};
struct Progress {
  std::uint64_t id = 0;
  std::uint64_t job = 0;
  JobState state = JobState::running;
  ProgressInfo progress;
  bool operator==(const Progress&) const = default;
};
struct Done {
  std::uint64_t id = 0;
  std::uint64_t job = 0;
  JobState state = JobState::done;  // done, failed or cancelled
  ProgressInfo progress;
  std::optional<std::string> message;  // why it failed
  bool operator==(const Done&) const = default;
};
struct Image {
  std::uint64_t id = 0;  // echoes the fetch
  std::uint64_t job = 0;
  std::uint64_t pass = 0;
  std::uint64_t spp = 0;
  std::uint32_t width = 0;
  std::uint32_t height = 0;
  std::string exr;  // payload
  bool operator==(const Image&) const = default;
};

// ---- workers (omega worker; docs/protocol.md "Workers") ----
// worker -> daemon: give me a unit. The daemon answers with work_unit when it has one (it may
// hold the request for as long as it has none); one request outstanding per connection.
struct WorkRequest {
  std::uint64_t id = 0;
  std::uint32_t threads = 1;
  std::string name;  // free text: host and pid, shown by `omega status`
  bool operator==(const WorkRequest&) const = default;
};
// daemon -> worker (echoes the work_request): render samples [begin, end) of the job's scene.
struct WorkUnit {
  std::uint64_t id = 0;
  std::uint64_t job = 0;
  std::uint64_t unit = 0;  // the unit's number within the job
  std::uint64_t begin = 0, end = 0;
  std::uint64_t seed = 0;
  std::string name;  // scene name (the scene is parsed as NAME.yaml among its assets)
  std::optional<std::string> integrator;
  std::optional<std::string> sampler;
  std::vector<AssetRef> assets;
  std::string scene;  // payload: the scene YAML
  bool operator==(const WorkUnit&) const = default;
};
// worker -> daemon: the bytes of an asset of a job it holds a unit of; answered by `asset`.
struct AssetRequest {
  std::uint64_t id = 0;
  std::uint64_t job = 0;
  std::string sha256;
  bool operator==(const AssetRequest&) const = default;
};
// worker -> daemon: a finished unit; payload: the part (omega render --samples A:B's EXR).
struct UnitResult {
  std::uint64_t id = 0;
  std::uint64_t job = 0;
  std::uint64_t unit = 0;
  std::uint64_t begin = 0, end = 0;
  double time_s = 0;
  double samples_per_s = 0;
  std::string part;  // payload
  bool operator==(const UnitResult&) const = default;
};
// daemon -> worker: stop rendering that unit (cancel, pause, halt); it is not wanted any more.
struct UnitStop {
  std::uint64_t id = 0;
  std::uint64_t job = 0;
  std::uint64_t unit = 0;
  std::string reason;
  bool operator==(const UnitStop&) const = default;
};

using Message = std::variant<Hello, Welcome, Auth, Ok, Error, Ping, Pong, Bye, Submit, NeedAssets,
                             Asset, Accepted, Status, JobInfoReply, List, JobList, Cancel, Pause,
                             Resume, SetPriority, Delete, Subscribe, Unsubscribe, Tile, Progress,
                             Done, Fetch, Image, WorkRequest, WorkUnit, AssetRequest, UnitResult,
                             UnitStop>;

MessageType type_of(const Message& m);
std::uint64_t id_of(const Message& m);

// Encoders: one per message type (overloads), plus the variant.
Frame encode(const Hello&);
Frame encode(const Welcome&);
Frame encode(const Auth&);
Frame encode(const Ok&);
Frame encode(const Error&);
Frame encode(const Ping&);
Frame encode(const Pong&);
Frame encode(const Bye&);
Frame encode(const Submit&);
Frame encode(const NeedAssets&);
Frame encode(const Asset&);
Frame encode(const Accepted&);
Frame encode(const Status&);
Frame encode(const JobInfoReply&);
Frame encode(const List&);
Frame encode(const JobList&);
template <MessageType T>
Frame encode(const JobRequest<T>&);
Frame encode(const SetPriority&);
Frame encode(const Tile&);
Frame encode(const Progress&);
Frame encode(const Done&);
Frame encode(const Image&);
Frame encode(const WorkRequest&);
Frame encode(const WorkUnit&);
Frame encode(const AssetRequest&);
Frame encode(const UnitResult&);
Frame encode(const UnitStop&);
Frame encode(const Message&);

// Decoders. decode_message dispatches on the frame's type; decode<T> expects that type.
Result<Message, DecodeError> decode_message(const DecodedFrame& f);
template <class T>
Result<T, DecodeError> decode(const DecodedFrame& f);

// Defined in messages_*.cpp for exactly the types of Message.
template <>
Result<Hello, DecodeError> decode<Hello>(const DecodedFrame& f);
template <>
Result<Welcome, DecodeError> decode<Welcome>(const DecodedFrame& f);
template <>
Result<Auth, DecodeError> decode<Auth>(const DecodedFrame& f);
template <>
Result<Ok, DecodeError> decode<Ok>(const DecodedFrame& f);
template <>
Result<Error, DecodeError> decode<Error>(const DecodedFrame& f);
template <>
Result<Ping, DecodeError> decode<Ping>(const DecodedFrame& f);
template <>
Result<Pong, DecodeError> decode<Pong>(const DecodedFrame& f);
template <>
Result<Bye, DecodeError> decode<Bye>(const DecodedFrame& f);
template <>
Result<Submit, DecodeError> decode<Submit>(const DecodedFrame& f);
template <>
Result<NeedAssets, DecodeError> decode<NeedAssets>(const DecodedFrame& f);
template <>
Result<Asset, DecodeError> decode<Asset>(const DecodedFrame& f);
template <>
Result<Accepted, DecodeError> decode<Accepted>(const DecodedFrame& f);
template <>
Result<Status, DecodeError> decode<Status>(const DecodedFrame& f);
template <>
Result<JobInfoReply, DecodeError> decode<JobInfoReply>(const DecodedFrame& f);
template <>
Result<List, DecodeError> decode<List>(const DecodedFrame& f);
template <>
Result<JobList, DecodeError> decode<JobList>(const DecodedFrame& f);
template <>
Result<Cancel, DecodeError> decode<Cancel>(const DecodedFrame& f);
template <>
Result<Pause, DecodeError> decode<Pause>(const DecodedFrame& f);
template <>
Result<Resume, DecodeError> decode<Resume>(const DecodedFrame& f);
template <>
Result<SetPriority, DecodeError> decode<SetPriority>(const DecodedFrame& f);
template <>
Result<Delete, DecodeError> decode<Delete>(const DecodedFrame& f);
template <>
Result<Subscribe, DecodeError> decode<Subscribe>(const DecodedFrame& f);
template <>
Result<Unsubscribe, DecodeError> decode<Unsubscribe>(const DecodedFrame& f);
template <>
Result<Tile, DecodeError> decode<Tile>(const DecodedFrame& f);
template <>
Result<Progress, DecodeError> decode<Progress>(const DecodedFrame& f);
template <>
Result<Done, DecodeError> decode<Done>(const DecodedFrame& f);
template <>
Result<Fetch, DecodeError> decode<Fetch>(const DecodedFrame& f);
template <>
Result<Image, DecodeError> decode<Image>(const DecodedFrame& f);
template <>
Result<WorkRequest, DecodeError> decode<WorkRequest>(const DecodedFrame& f);
template <>
Result<WorkUnit, DecodeError> decode<WorkUnit>(const DecodedFrame& f);
template <>
Result<AssetRequest, DecodeError> decode<AssetRequest>(const DecodedFrame& f);
template <>
Result<UnitResult, DecodeError> decode<UnitResult>(const DecodedFrame& f);
template <>
Result<UnitStop, DecodeError> decode<UnitStop>(const DecodedFrame& f);
extern template Frame encode(const JobRequest<MessageType::cancel>&);
extern template Frame encode(const JobRequest<MessageType::pause>&);
extern template Frame encode(const JobRequest<MessageType::resume>&);
extern template Frame encode(const JobRequest<MessageType::delete_job>&);
extern template Frame encode(const JobRequest<MessageType::subscribe>&);
extern template Frame encode(const JobRequest<MessageType::unsubscribe>&);
extern template Frame encode(const JobRequest<MessageType::fetch>&);

}  // namespace omega::protocol
