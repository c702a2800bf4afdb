#include "scene/triangle_mesh.h"

#include <fmt/format.h>

#include <cmath>

#include "scene/scene_error.h"

namespace omega {

namespace {

std::string prefix(const SourceLoc& loc) {
    if (loc.key.empty()) return fmt::format("{}:{}: ", loc.file, loc.line);
    return fmt::format("{}:{}: {}: ", loc.file, loc.line, loc.key);
}

// Mitsuba 3's cube mesh maps every face onto [0, 1]^2; these are the affine maps its vertex table
// implies (checked corner by corner in triangle_mesh_test.cpp).
Vec2 cube_face_uv(int axis, int sign, const Vec3& p) {
    auto h = [](float c) { return 0.5f * (c + 1.f); };  // [-1, 1] -> [0, 1]
    switch (axis * 2 + (sign > 0)) {
        case 0: return {h(p.y), h(p.z)};   // -x
        case 1: return {h(p.y), h(-p.z)};  // +x
        case 2: return {h(p.z), h(p.x)};   // -y
        case 3: return {h(-p.x), h(-p.z)}; // +y
        case 4: return {h(-p.y), h(p.x)};  // -z
        default: return {h(p.y), h(p.x)};  // +z
    }
}

}  // namespace

Vec2 disk_uv(Vec2 xy) {
    float r = std::sqrt(xy.x * xy.x + xy.y * xy.y);
    float v = std::atan2(xy.y, xy.x) * kInv2Pi;
    if (v < 0) v += 1.f;
    return {r, v};
}

TriangleMesh make_rectangle() {
    TriangleMesh m;
    m.positions = {{-1, -1, 0}, {1, -1, 0}, {1, 1, 0}, {-1, 1, 0}};
    m.normals.assign(4, Vec3{0, 0, 1});
    for (const Vec3& p : m.positions) m.uvs.push_back({0.5f * p.x + 0.5f, 0.5f * p.y + 0.5f});
    m.indices = {0, 1, 2, 0, 2, 3};  // counter-clockwise seen from +z
    return m;
}

TriangleMesh make_cube() {
    // Each face has its own 4 vertices so that normals stay sharp at the edges.
    TriangleMesh m;
    for (int axis = 0; axis < 3; ++axis)
        for (int sign : {-1, 1}) {
            Vec3 n{0, 0, 0};
            n[axis] = float(sign);
            // (u, v, n) is right-handed, so u x v = n and the quad's winding faces outward.
            Vec3 u{0, 0, 0}, v{0, 0, 0};
            u[(axis + 1) % 3] = 1;
            v[(axis + 2) % 3] = float(sign);
            uint32_t base = uint32_t(m.positions.size());
            for (auto [a, b] : {std::pair{-1.f, -1.f}, {1.f, -1.f}, {1.f, 1.f}, {-1.f, 1.f}}) {
                Vec3 p = n + u * a + v * b;
                m.positions.push_back(p);
                m.normals.push_back(n);
                m.uvs.push_back(cube_face_uv(axis, sign, p));
            }
            for (uint32_t i : {0u, 1u, 2u, 0u, 2u, 3u}) m.indices.push_back(base + i);
        }
    return m;
}

TriangleMesh make_disk(int segments) {
    segments = std::max(segments, 3);
    TriangleMesh m;
    m.positions.push_back({0, 0, 0});
    for (int i = 0; i < segments; ++i) {
        double phi = 2 * kPiD * i / segments;
        m.positions.push_back({float(std::cos(phi)), float(std::sin(phi)), 0.f});
    }
    m.normals.assign(m.positions.size(), Vec3{0, 0, 1});
    for (const Vec3& p : m.positions) m.uvs.push_back({p.x, p.y});
    for (int i = 0; i < segments; ++i) {
        m.indices.push_back(0);
        m.indices.push_back(uint32_t(1 + i));
        m.indices.push_back(uint32_t(1 + (i + 1) % segments));
    }
    return m;
}

size_t bake_mesh(TriangleMesh& mesh, const Transform& to_world, bool flip_normals, bool drop_degenerate,
                 const SourceLoc& loc, const std::string& what) {
    const std::string at = prefix(loc);
    if (mesh.indices.size() % 3 != 0) throw SceneError(at + what + ": index count is not a multiple of 3");
    if (!mesh.normals.empty() && mesh.normals.size() != mesh.positions.size())
        throw SceneError(at + what + ": normal count differs from vertex count");
    if (!mesh.uvs.empty() && mesh.uvs.size() != mesh.positions.size())
        throw SceneError(at + what + ": uv count differs from vertex count");

    // A non-finite vertex is reported with the first triangle that uses it (below): that is what
    // a user finds in a modelling tool. One no triangle uses is harmless and zeroed for Embree.
    std::vector<uint8_t> bad_vertex(mesh.positions.size(), 0);
    for (size_t i = 0; i < mesh.positions.size(); ++i) {
        Vec3d p = to_world.point(Vec3d(mesh.positions[i]));
        Vec3 pf(p);
        if (!is_finite(pf)) {
            bad_vertex[i] = 1;
            pf = Vec3(0.f);
        }
        mesh.positions[i] = pf;
    }
    for (size_t i = 0; i < mesh.normals.size(); ++i) {
        Vec3d n = to_world.normal(Vec3d(mesh.normals[i]));
        double len = length(n);
        if (!(len > 0) || !std::isfinite(len))
            throw SceneError(fmt::format("{}{} vertex {} has an invalid normal (use face_normals: true to ignore them)",
                                         at, what, i));
        n = n / len;
        mesh.normals[i] = Vec3(flip_normals ? -n : n);
    }

    // A mirroring transform reverses the winding; undo that so the geometric normal (from the
    // winding) agrees with the transformed shading normal, then flip both if asked.
    bool reverse = (to_world.fwd.det3() < 0) != flip_normals;
    size_t dropped = 0, out = 0;
    const size_t nv = mesh.positions.size();
    for (size_t t = 0; t < mesh.triangle_count(); ++t) {
        uint32_t a = mesh.indices[3 * t], b = mesh.indices[3 * t + 1], c = mesh.indices[3 * t + 2];
        if (a >= nv || b >= nv || c >= nv)
            throw SceneError(fmt::format("{}{} triangle {} has a vertex index out of range", at, what, t));
        for (uint32_t v : {a, b, c})
            if (bad_vertex[v])
                throw SceneError(fmt::format("{}{} triangle {} has a non-finite vertex (vertex {})", at, what, t, v));
        Vec3d pa(mesh.positions[a]), pb(mesh.positions[b]), pc(mesh.positions[c]);
        double area2 = length(cross(pb - pa, pc - pa));
        if (!(area2 > 0) || !std::isfinite(area2)) {
            if (!drop_degenerate)
                throw SceneError(fmt::format(
                    "{}{} triangle {} is degenerate (zero area; drop_degenerate: true, the default, drops such "
                    "triangles)",
                    at, what, t));
            ++dropped;
            continue;
        }
        if (reverse) std::swap(b, c);
        mesh.indices[out++] = a;
        mesh.indices[out++] = b;
        mesh.indices[out++] = c;
    }
    mesh.indices.resize(out);
    if (mesh.indices.empty()) throw SceneError(at + what + ": no triangles left");
    return dropped;
}

}  // namespace omega
