#include "protocol/tools/examples.h"

#include <cstdio>

namespace omega::protocol::examples {

namespace {
const std::string kMesh = "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n";
const std::string kMeshSha = "697b00ab13410c52a542d2e9c63711fcc04e9cbf6c0d3439a9b43cc812e6e713";
// Stand-in for EXR bytes: the EXR magic and version, then nothing. Real tiles carry a whole file.
const std::string kExr = std::string("\x76\x2f\x31\x01\x02\x00\x00\x00", 8);

ProgressInfo sample_progress(bool with_error) {
  ProgressInfo p;
  p.pass = 3;
  p.spp = 12;
  p.elapsed_s = 4.25;
  if (with_error) p.rel_error = 0.031;
  p.samples_per_s = 1.5e6;
  return p;
}

JobInfo sample_job() {
  JobInfo j;
  j.job = 42;
  j.name = "cornell";
  j.state = JobState::running;
  j.priority = 5;
  j.owner = "alice";
  j.halt.spp = 64;
  j.progress = sample_progress(true);
  return j;
}
}  // namespace

std::vector<Example> all() {
  std::vector<Example> v;
  v.push_back({"hello", Hello{1, 1, 1, "omega/0.1"}});
  v.push_back({"welcome (unix socket, peer credentials)",
               Welcome{1, 1, "omegad/0.1", AuthMethod::peer, std::nullopt, std::string("1000")}});
  v.push_back({"welcome (TCP, HMAC challenge)",
               Welcome{1, 1, "omegad/0.1", AuthMethod::hmac_sha256,
                       std::string("8f3a8f3a8f3a8f3a8f3a8f3a8f3a8f3a8f3a8f3a8f3a8f3a8f3a8f3a8f3a8f3a"),
                       std::nullopt}});
  v.push_back({"auth", Auth{2, "alice", "26b1d5bb85c36f62ee57db9aa7a7c24e7333efbaa9f211742be5491a046287df"}});
  v.push_back({"ok", Ok{2}});
  v.push_back({"error", Error{3, ErrorCode::scene_invalid, "scene.yaml:4: sensor.fov: expected a number"}});
  v.push_back({"ping", Ping{4}});
  v.push_back({"pong", Pong{4}});
  v.push_back({"bye", Bye{0}});
  {
    Submit s;
    s.id = 5;
    s.name = "bunny";
    s.priority = 0;
    s.halt.spp = 64;
    s.halt.time_s = 30.0;
    s.seed = 7;
    s.integrator = "bdpt";
    s.assets.push_back(AssetRef{"meshes/tri.obj", kMeshSha, kMesh.size()});
    s.scene = "omega: 1\nshapes:\n  - {type: mesh, file: meshes/tri.obj}\n";
    v.push_back({"submit", s});
  }
  v.push_back({"need_assets", NeedAssets{5, {kMeshSha}}});
  v.push_back({"asset", Asset{5, kMeshSha, kMesh}});
  v.push_back({"accepted", Accepted{5, 42}});
  v.push_back({"status", Status{6, 42}});
  v.push_back({"job_info", JobInfoReply{6, sample_job()}});
  v.push_back({"list", List{7}});
  v.push_back({"job_list", JobList{7, {sample_job()}}});
  v.push_back({"cancel", Cancel{8, 42}});
  v.push_back({"pause", Pause{9, 42}});
  v.push_back({"resume", Resume{10, 42}});
  v.push_back({"set_priority", SetPriority{11, 42, -3}});
  v.push_back({"delete", Delete{12, 42}});
  v.push_back({"subscribe", Subscribe{13, 42}});
  v.push_back({"unsubscribe", Unsubscribe{14, 42}});
  v.push_back({"tile", Tile{13, 42, Rect{32, 0, 64, 32}, 3, 12, 3, kExr}});
  v.push_back({"progress", Progress{13, 42, JobState::running, sample_progress(true)}});
  v.push_back({"done", Done{13, 42, JobState::done, sample_progress(false), std::nullopt}});
  v.push_back({"fetch", Fetch{15, 42}});
  v.push_back({"image", Image{15, 42, 3, 12, 512, 512, kExr}});
  v.push_back({"work_request", WorkRequest{1, 4, "node17:4242"}});
  {
    WorkUnit u;
    u.id = 1;
    u.job = 42;
    u.unit = 3;
    u.begin = 48;
    u.end = 64;
    u.seed = 7;
    u.name = "bunny";
    u.integrator = "bdpt";
    u.assets.push_back(AssetRef{"meshes/tri.obj", kMeshSha, kMesh.size()});
    u.scene = "omega: 1\nshapes:\n  - {type: mesh, file: meshes/tri.obj}\n";
    v.push_back({"work_unit", u});
  }
  v.push_back({"asset_request", AssetRequest{2, 42, kMeshSha}});
  v.push_back({"unit_result", UnitResult{3, 42, 3, 48, 64, 2.5, 1.2e6, kExr}});
  v.push_back({"unit_stop", UnitStop{0, 42, 3, "cancelled"}});
  return v;
}

std::string hex_dump(std::string_view bytes) {
  std::string out;
  char buf[32];
  for (std::size_t off = 0; off < bytes.size(); off += 16) {
    std::snprintf(buf, sizeof buf, "%08zx ", off);
    out += buf;
    std::string ascii;
    for (std::size_t i = 0; i < 16; ++i) {
      if (i == 8) out += ' ';
      if (off + i < bytes.size()) {
        auto c = static_cast<unsigned char>(bytes[off + i]);
        std::snprintf(buf, sizeof buf, " %02x", c);
        out += buf;
        ascii += (c >= 0x20 && c < 0x7f) ? static_cast<char>(c) : '.';
      } else {
        out += "   ";
      }
    }
    out += "  |" + ascii + "|\n";
  }
  return out;
}

std::string markdown_block(const Example& e) {
  return "```\n" + hex_dump(encode_frame(encode(e.message))) + "```\n";
}

}  // namespace omega::protocol::examples
