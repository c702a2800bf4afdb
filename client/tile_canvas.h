#pragma once
// Assembles the tiles `watch` receives into the whole image and writes it as an EXR with the
// same layout as the daemon's `fetch` image (data window = the rendered region, display window =
// the full film), atomically (temp file + rename).
#include <cstdint>
#include <map>
#include <string>
#include <tuple>

#include "film/film.h"
#include "protocol/messages.h"

namespace omega::client {

class TileCanvas {
public:
    // Applies a tile unless a newer version of its rect was already applied; returns whether it
    // was. Throws ClientError (exit 1) for a payload that is not an EXR matching its rect, or a
    // film size different from earlier tiles'.
    bool apply(const protocol::Tile& t);

    bool empty() const { return versions_.empty(); }
    size_t tiles() const { return versions_.size(); }
    // The image so far: data window = the bounding box of the rects received (the crop once
    // every tile has arrived), pixels not covered yet are 0. Attributes are the newest tile's.
    ExrImage image() const;
    ExrMeta meta() const { return meta_; }
    std::vector<uint8_t> encode() const;
    void write(const std::string& path) const;  // atomic; throws std::runtime_error

private:
    using Key = std::tuple<uint32_t, uint32_t, uint32_t, uint32_t>;
    int width_ = 0, height_ = 0;  // display window
    // Per display-window row, 3 floats per pixel, allocated when a tile first touches the row: a
    // tile (from the network) that claims a huge film costs only the rows it covers. Rows no tile
    // touched read as 0.
    std::vector<std::vector<float>> rgb_, var_;
    std::vector<float>& row(std::vector<std::vector<float>>& rows, int y);
    int bx0_ = 0, by0_ = 0, bx1_ = 0, by1_ = 0;  // bounding box of applied rects
    std::map<Key, uint64_t> versions_;
    std::tuple<uint64_t, uint64_t, uint64_t> newest_{};  // (pass, spp, version) of the meta's tile
    bool have_meta_ = false;
    ExrMeta meta_;
};

// The omega.* attributes of a decoded EXR back as ExrMeta (inverse of what write_exr writes).
ExrMeta meta_from_attributes(const std::map<std::string, std::string>& attrs);

}  // namespace omega::client
