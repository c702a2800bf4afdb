#pragma once
// Triangle geometry as loaded or generated, before it is handed to Embree.
#include <cstdint>
#include <string>
#include <vector>

#include "math/transform.h"
#include "math/vec.h"
#include "scene/scene_desc.h"

namespace omega {

struct TriangleMesh {
    std::vector<Vec3> positions;
    std::vector<Vec3> normals;      // per vertex shading normals, empty = flat shading
    std::vector<uint32_t> indices;  // 3 per triangle
    size_t triangle_count() const { return indices.size() / 3; }
};

// Object-space primitives of scene format v1.
TriangleMesh make_rectangle();             // [-1,1]^2 in z = 0, normal +z
TriangleMesh make_cube();                  // [-1,1]^3, outward normals
TriangleMesh make_disk(int segments = 64); // unit disk in z = 0, normal +z

// Loads OBJ, PLY or glTF through Assimp (all meshes in the file merged, triangulated).
// Throws SceneError naming `loc` and the file on failure.
TriangleMesh load_mesh_file(const std::string& path, const SourceLoc& loc);

// Applies to_world (normals by the inverse transpose, in double), flips normals if asked, and
// validates: non-finite positions and zero-area triangles are errors naming the shape and the
// triangle, unless drop_degenerate is set, in which case they are removed and counted.
// Returns the number of dropped triangles.
size_t bake_mesh(TriangleMesh& mesh, const Transform& to_world, bool flip_normals, bool drop_degenerate,
                 const SourceLoc& loc, const std::string& what);

}  // namespace omega
