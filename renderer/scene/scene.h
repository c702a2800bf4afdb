#pragma once
// The renderable scene: world-space geometry in one Embree BVH, materials, lights and the
// sensor. Built once from a SceneDesc (scene_builder.cpp), then read-only: every method is safe
// to call from any number of render threads at once.
#include <embree3/rtcore.h>

#include <functional>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "bsdf/bsdf.h"
#include "light/light.h"
#include "math/vec.h"
#include "sampling/distribution.h"
#include "scene/ray.h"
#include "light/emitter_plane.h"
#include "scene/parallelogram.h"
#include "scene/scene_desc.h"
#include "scene/sphere_geometry.h"
#include "scene/triangle_mesh.h"
#include "sensor/sensor.h"
#include "texture/bitmap_texture.h"

namespace omega {

enum class ShapeKind : uint8_t { Triangles, Sphere };

// How Scene::intersect fills SurfaceHit::uv. None unless the shape's material is textured.
enum class UvMap : uint8_t {
    None,
    Vertex,  // barycentric interpolation of mesh.uvs; the barycentrics (b1, b2) if there are none
    Disk,    // mesh.uvs hold object-space (x, y); interpolated, then disk_uv()
    Sphere,  // Mitsuba's spherical map in the sphere's own frame (sphere_axes)
};

struct Shape {
    ShapeKind kind = ShapeKind::Triangles;
    uint32_t material = 0;  // index into Scene::materials()
    int32_t light = -1;     // its area light, or -1
    bool flip_normals = false;      // spheres only: triangle meshes are baked flipped
    TriangleMesh mesh;      // world space (triangles)
    std::vector<Vec3> face_normals;  // unit geometric normal per triangle (from the baked winding)
    SphereData sphere;      // world space (sphere); Embree keeps a pointer to it
    UvMap uv_map = UvMap::None;
    // Mask (MaterialDesc::opacity): a hit survives with probability opacity (or the texture's
    // value at its uv); Embree filter functions drop the others (scene.cpp). 1 and null: opaque.
    float opacity = 1.f;
    const BitmapTexture* opacity_tex = nullptr;
    bool masked() const { return opacity < 1.f || opacity_tex != nullptr; }
    // Bump map (MaterialDesc::bump_texture): Scene::intersect tilts the shading normal.
    const BitmapTexture* bump_tex = nullptr;
    float bump_scale = 1.f;
    Vec3 sphere_axes[3];    // sphere: unit world directions of its local x, y, z (for uv)
    double area = 0;                     // world-space surface area
    float inv_area = 0;                  // float(1 / area): light sampling's density, without a division per sample
    DiscreteDistribution tri_by_area;    // triangles, for uniform area sampling
    std::optional<Parallelogram> parallelogram;  // an emitter that is one: sampled as it instead
    std::optional<EmitterPlane> emitter_plane;   // a one-sided flat emitter: NEE skips points behind it
    std::string name;                    // for messages: "shapes[3]"
};

struct SceneBounds {
    Vec3 lo{kInfinity, kInfinity, kInfinity}, hi{-kInfinity, -kInfinity, -kInfinity};
    Vec3 center() const { return (lo + hi) * 0.5f; }
    float radius() const { return 0.5f * length(hi - lo); }
    bool empty() const { return lo.x > hi.x; }
};

// Makes Embree skip the hits on a masked triangle shape that its opacity drops (scene.cpp).
void attach_mask_filter(RTCGeometry g, const Shape& sh);

class Scene {
public:
    // Loads resources and builds the BVH. Every file is read through the description's
    // FileGate (desc.files). Throws SceneError for bad content (degenerate meshes...) and
    // std::runtime_error for Embree failures. `cancelled` is polled between resources, inside
    // Assimp's parse and during the BVH build; when it says true, build throws BuildCancelled.
    static std::unique_ptr<Scene> build(const SceneDesc& desc, const std::function<bool()>& cancelled = {});
    ~Scene();
    Scene(const Scene&) = delete;
    Scene& operator=(const Scene&) = delete;

    // Closest hit within (0, ray.tmax). Thread-safe.
    bool intersect(const Ray& ray, SurfaceHit& hit) const;
    // Any hit within (0, ray.tmax). Thread-safe.
    bool occluded(const Ray& ray) const;
    // Up to kPacket independent rays in one Embree packet query (rtcIntersect8 / rtcOccluded8):
    // found[i], hits[i] and occluded[i] are what intersect() and occluded() give for rays[i],
    // bit for bit (scene/packet_query_test.cpp), so a tracer may batch rays without changing an
    // image. bench/throughput measures the headroom: incoherent rays ran 1.19x faster in packets
    // of 8, and a bare loop with 8 paths in flight per thread 1.17x (Cornell box) to 1.37x
    // (indirect-room) faster than one ray at a time. Thread-safe.
    // No tracer uses them yet, because neither batching that was tried paid:
    // - BDPT's shadow rays of one sample in one packet (0dff7d2's session): 0.98-1.03.
    // - The path tracer with 8 paths in flight per thread, its walk cut into resumable steps,
    //   the paths' next rays in one intersect_packet (bench/ab_cores.sh against one path at a
    //   time, same bits): indirect-room 1.02, Cornell 0.95. The same lanes with one query per ray
    //   read 0.89: 8 interleaved walks, each with its state in memory rather than in registers,
    //   cost 11% and the packets won back about 13%.
    static constexpr size_t kPacket = 8;
    void intersect_packet(std::span<const Ray> rays, SurfaceHit* hits, bool* found) const;
    void occluded_packet(std::span<const Ray> rays, bool* occluded) const;

    // What the build accepted but the user should know (degenerate triangles dropped), one line
    // per shape, "FILE:LINE: shapes[i] 'name' (mesh.obj): ...". Callers add them to the scene's
    // warnings, which reach the EXR header and the daemon's job.
    const std::vector<std::string>& warnings() const { return warnings_; }

    const std::vector<Shape>& shapes() const { return shapes_; }
    const std::vector<Bsdf>& materials() const { return materials_; }
    const std::vector<Light>& lights() const { return lights_; }
    const DiscreteDistribution& light_selection() const { return light_select_; }
    int environment_light() const { return env_light_; }  // index or -1
    const Sensor& sensor() const { return sensor_; }
    const SceneDesc& desc() const { return desc_; }
    const SceneBounds& bounds() const { return bounds_; }
    // The material as described; its textures are not yet looked up.
    const Bsdf& bsdf_of(const SurfaceHit& h) const { return materials_[shapes_[h.shape].material]; }
    // The BSDF at the hit, textures looked up at h.uv (see resolve_bsdf): what rendering evaluates.
    const Bsdf& bsdf_at(const SurfaceHit& h, Bsdf& tmp) const { return resolve_bsdf(bsdf_of(h), h.uv, tmp); }
    // The raw BVH, for benchmarks that measure Embree's own rate on the same scene.
    RTCScene embree_scene() const { return rtc_; }

private:
    Scene() = default;
    // What intersect() makes of Embree's closest hit (geom, prim, barycentrics u, v, distance t).
    void fill_hit(const Ray& ray, float t, uint32_t geom, uint32_t prim, float u, float v, SurfaceHit& hit) const;
    void add_embree_geometry(const std::function<bool()>& cancelled);

    SceneDesc desc_;
    std::vector<std::string> warnings_;
    RTCDevice device_ = nullptr;
    RTCScene rtc_ = nullptr;
    std::vector<Shape> shapes_;
    std::vector<Bsdf> materials_;
    std::vector<std::unique_ptr<BitmapTexture>> textures_;  // materials_ point into these
    std::vector<Light> lights_;
    DiscreteDistribution light_select_;
    int env_light_ = -1;
    Sensor sensor_;
    SceneBounds bounds_;
};

}  // namespace omega
