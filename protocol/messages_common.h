#pragma once
// Internal helpers shared by the messages_*.cpp files.
#include <string>

#include "protocol/header_writer.h"
#include "protocol/messages.h"

namespace omega::protocol::detail {

// Opens the header mapping with the two fields every frame starts with.
HeaderWriter begin_header(MessageType t, std::uint64_t id);
Frame finish(HeaderWriter& w, std::string payload = {});

// Checks the frame's type and that types without payload carry none.
std::optional<Failure<DecodeError>> check_frame(const DecodedFrame& f, MessageType expected);

void write_halt(HeaderWriter& w, const Halt& h);
void write_progress(HeaderWriter& w, const ProgressInfo& p);
void write_job_info_fields(HeaderWriter& w, const JobInfo& j);

Halt read_halt(FieldReader& r);
ProgressInfo read_progress(FieldReader& r);
JobState read_job_state(FieldReader& r, std::string_view key);
JobInfo read_job_info_fields(FieldReader& r);
std::string read_sha256(FieldReader& r, std::string_view key);
// The asset list of submit and work_unit (safe relative names, no duplicates).
void write_assets(HeaderWriter& w, const std::vector<AssetRef>& assets);
std::vector<AssetRef> read_assets(FieldReader& r);
// An optional integrator/sampler name: [a-z0-9_], at most 64 bytes.
std::optional<std::string> read_identifier(FieldReader& r, std::string_view key);
void write_worker_infos(HeaderWriter& w, const std::vector<WorkerInfo>& ws);
std::vector<WorkerInfo> read_worker_infos(FieldReader& r);

template <class T>
Result<T, DecodeError> finish_decode(FieldReader& r, T&& value) {
  if (!r.ok()) return r.failure();
  return std::forward<T>(value);
}

}  // namespace omega::protocol::detail
