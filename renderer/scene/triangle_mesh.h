#pragma once
// Triangle geometry as loaded or generated, before it is handed to Embree.
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "math/transform.h"
#include "math/vec.h"
#include "scene/scene_desc.h"

namespace omega {

class FileGate;

struct TriangleMesh {
    std::vector<Vec3> positions;
    std::vector<Vec3> normals;      // per vertex shading normals, empty = flat shading
    // Per vertex surface coordinates, empty = none. For the disk they hold the object-space (x, y)
    // (linear over each triangle), turned into Mitsuba's polar (r, phi / 2 pi) after interpolation.
    std::vector<Vec2> uvs;
    std::vector<uint32_t> indices;  // 3 per triangle
    size_t triangle_count() const { return indices.size() / 3; }
};

// Object-space primitives of scene format v1.
// Their uvs follow Mitsuba 3: rectangle ((x + 1) / 2, (y + 1) / 2); each cube face onto [0, 1]^2
// as Mitsuba's cube mesh lays it out; the disk's local (x, y) (see TriangleMesh::uvs).
TriangleMesh make_rectangle();             // [-1,1]^2 in z = 0, normal +z
TriangleMesh make_cube();                  // [-1,1]^3, outward normals
TriangleMesh make_disk(int segments = 64); // unit disk in z = 0, normal +z

// Mitsuba's disk uv from the object-space point: (radius, angle / 2 pi in [0, 1)).
Vec2 disk_uv(Vec2 local_xy);

struct MeshFileOptions {
    // Mitsuba's default, true: turns the files' v-up convention into the textures' v-down one.
    bool flip_tex_coords = true;
    std::string written;  // the file as the scene wrote it, for messages
    // Polled while Assimp parses; true aborts the import with BuildCancelled.
    std::function<bool()> cancelled;
    // Called with the absolute path of every file read, the mesh file first (the client's
    // asset scan learns an OBJ's mtllib or a glTF's buffers this way).
    std::function<void(const std::string&)> on_read;
    // Only these of the file's meshes (Assimp's indices); empty = all. An index the file lacks
    // is an error naming it.
    std::vector<int> parts;
};

// Loads OBJ, PLY or glTF through Assimp (all meshes in the file merged, triangulated), with the
// first uv channel if the file has one. Every file Assimp opens, the mesh file and whatever it
// names inside itself, is read through `gate`. A confined gate's refusal of any of them refuses
// the mesh; an unconfined one lets Assimp carry on without it (as it does for a missing .mtl).
// Throws SceneError naming `loc` and the file on failure.
TriangleMesh load_mesh_file(const FileGate& gate, const std::string& path, const SourceLoc& loc,
                            const MeshFileOptions& options = {});

// Applies to_world (normals by the inverse transpose, in double), flips normals if asked, and
// validates: a triangle with a non-finite vertex is an error naming the shape (and file) and the
// triangle; zero-area triangles are too unless drop_degenerate is set, in which case they are
// removed and counted (exported meshes routinely hold a few).
// Returns the number of dropped triangles.
size_t bake_mesh(TriangleMesh& mesh, const Transform& to_world, bool flip_normals, bool drop_degenerate,
                 const SourceLoc& loc, const std::string& what);

}  // namespace omega
