#pragma once
// What a scene file says, after parsing and validation, before any resource is loaded.
// Parsing (scene_parser) fills this; resource loading (scene_builder) turns it into a Scene.
// Every entry keeps the file and line it came from so later errors can point back at it.
#include <array>
#include <map>
#include <memory>
#include <limits>
#include <optional>
#include <string>
#include <vector>

#include "bsdf/bsdf.h"
#include "math/transform.h"
#include "math/vec.h"
#include "pathspace/lpe.h"
#include "sampling/sampler_type.h"
#include "texture/texture_types.h"

namespace omega {

class FileGate;

struct SourceLoc {
    std::string file;
    int line = 0;  // 1-based; 0 when unknown
    std::string key;  // dotted key path, e.g. "shapes[2]"; empty when unknown
};

enum class IntegratorType { Path, Light, Bdpt };

// The name used in scene files, on the command line, in the protocol and in EXR headers.
inline const char* integrator_name(IntegratorType t) {
    switch (t) {
        case IntegratorType::Path: return "path";
        case IntegratorType::Light: return "light";
        case IntegratorType::Bdpt: return "bdpt";
    }
    return "path";
}

struct IntegratorDesc {
    IntegratorType type = IntegratorType::Path;
    int max_depth = -1;  // edges; -1 = unbounded (Russian roulette ends paths)
    int rr_depth = 5;    // edges after which Russian roulette starts
    // Tests only (no scene-file key): false makes the path integrator sample BSDFs alone, without
    // next-event estimation, so emitters hit count with MIS weight 1 (strategy s = 0 alone). Its
    // per-sample variance then has closed forms (tests/stability/furnace_variance_test.cpp).
    // Other integrators reject false.
    bool light_sampling = true;
    // Tests only (no scene-file key): false leaves out the planar-mirror connector
    // (pathspace/mirror_connector.h), to check its MIS against the plain strategies.
    bool mirror_connector = true;
    // Scene key `sampler: {type: sobol | independent}` (top level, beside `integrator`); it lives
    // here so that every place that hands an IntegratorDesc to a render carries it along.
    SamplerType sampler = SamplerType::Sobol;
};

enum class FilterType { Box, Tent, Gaussian };

struct FilmDesc {
    int width = 512, height = 512;
    FilterType filter = FilterType::Box;
    float filter_radius = 0.5f;  // pixels; box 0.5, tent 1, gaussian 2 (stddev 0.5) by default
    float gaussian_stddev = 0.5f;
    // [x0, y0, x1, y1) in pixels; defaults to the whole film.
    std::array<int, 4> crop{0, 0, 0, 0};
    bool has_crop = false;
    // Light path expression outputs (film key `aov`, `omega render --aov`), in file order; each
    // is an image of its own (pathspace/lpe.h, integrator/aov_images.h).
    std::vector<AovDesc> aovs;
    // The measurement-contribution breakdown (film key `breakdown`, `omega render --breakdown`;
    // integrator/breakdown.h): classes up to `length` edges, over the crop or a pixel box.
    struct Breakdown {
        int length = 6;
        std::optional<std::array<int, 4>> box;  // [x0, y0, x1, y1)
    };
    std::optional<Breakdown> breakdown;
};

// When a render stops: whichever given condition is met first. None given = 64 spp.
struct HaltDesc {
    std::optional<long long> spp;
    std::optional<double> time_s;
    std::optional<double> target_error;
};

enum class SensorType { Perspective, ThinLens, Orthographic };

struct SensorDesc {
    SensorType type = SensorType::Perspective;
    float fov = 45.f;        // degrees
    char fov_axis = 'x';     // 'x' or 'y'
    Mat4 to_world;           // local frame: looks along +z, +y up, +x is the image's left
    float aperture_radius = 0.f;  // thin_lens, world units
    float focus_distance = 1.f;   // thin_lens, world units
    float near_clip = 0.f;        // world units along the ray
    // Mitsuba's far clipping plane, kept only to warn: Omega never clips far away, and the build
    // says so when geometry lies beyond it (infinity: none given).
    float far_clip = std::numeric_limits<float>::infinity();
    FilmDesc film;
    HaltDesc halt;
    SourceLoc loc;
};

// An image that is no file of its own: a .glb's bufferView image or a glTF data: uri, held as the
// encoded bytes the scene file carries (PNG, JPEG, ...). It is decoded from memory like any
// image the gate read, so nothing is ever opened by its name. Immutable; shared by every texture
// that uses it.
struct EmbeddedImage {
    std::string bytes;
    // A file name for it, unique within its scene and deterministic ("checker.png", "image3.jpg"):
    // what `omega import` and `omega submit` write it as (scene_writer.h).
    std::string name;
};

// A `{type: bitmap, file: ...}` value: Mitsuba's bitmap texture. The file is checked through the
// scene's FileGate at parse time and decoded when a shape's material needs it (Scene::build).
// A texture: a bitmap file, or (checker) Mitsuba's procedural checkerboard, which uses only
// to_uv, color0 and color1, or (embedded) an image carried in memory.
struct BitmapDesc {
    // Absolute path (empty for a checkerboard). Embedded: a label, "<scene file>#images[N]", which
    // no loader opens; it keeps images that share one file apart in Scene::build's cache.
    std::string file;
    TexFilter filter = TexFilter::Bilinear;
    TexWrap wrap = TexWrap::Repeat;
    bool raw = false;  // false: 8/16-bit data is sRGB-decoded to linear
    UvTransform to_uv;
    SourceLoc loc;     // of the bitmap mapping, for load errors
    std::string written;  // the file as the scene wrote it, for messages
    SourceLoc file_loc;   // of the file value itself (key "....file")
    bool checker = false;
    Rgb color0{0.4f, 0.4f, 0.4f}, color1{0.2f, 0.2f, 0.2f};  // Mitsuba's defaults
    // Set: the image is these bytes, not the file (which for_each_scene_file then passes over).
    std::shared_ptr<const EmbeddedImage> embedded;
};

struct MaterialDesc {
    std::string name;
    Bsdf bsdf;
    SourceLoc loc;
    // Diffuse and plastic: the (diffuse) reflectance is this bitmap (the bsdf's own value is then unused).
    // Last, so that {name, bsdf, loc} still initialises an untextured material.
    std::optional<BitmapDesc> reflectance_texture;
    // Conductor, dielectric, thin dielectric, plastic: specular_reflectance is this texture.
    std::optional<BitmapDesc> specular_texture;
    // Dielectric, thin dielectric: specular_transmittance is this texture.
    std::optional<BitmapDesc> transmittance_texture;
    // Conductor, dielectric, rough plastic, rough diffuse: the isotropic roughness alpha is this
    // texture's scalar per hit (resolve_textured; the bsdf's alpha then holds its mean).
    std::optional<BitmapDesc> alpha_texture;
    // Mask (Mitsuba's `mask` wrapper, YAML `opacity`): the surface is there with probability
    // opacity (1 = opaque), a constant or opacity_texture's first channel; see Scene::intersect.
    float opacity = 1.f;
    std::optional<BitmapDesc> opacity_texture;
    // Bump map (Mitsuba's `bumpmap` wrapper): height = bump_scale x the texture's first channel.
    std::optional<BitmapDesc> bump_texture;
    float bump_scale = 1.f;

    // Every texture slot, in the order the writer writes them (one list for the writer, the
    // asset scan and the file checks).
    std::array<const std::optional<BitmapDesc>*, 6> texture_slots() const {
        return {&reflectance_texture, &specular_texture, &transmittance_texture, &alpha_texture, &opacity_texture,
                &bump_texture};
    }
};

struct EmitterDesc {
    Rgb radiance{0.f, 0.f, 0.f};  // W / (m^2 sr)
    bool two_sided = false;       // emit on both sides; otherwise only on the +normal side
};

enum class ShapeType { Mesh, Rectangle, Cube, Sphere, Disk };

struct ShapeDesc {
    ShapeType type = ShapeType::Rectangle;
    std::string name;          // optional, for messages (Mitsuba's id)
    Mat4 to_world;
    std::string file;          // mesh: absolute path, checked through the FileGate at parse time
    Vec3d center{0, 0, 0};     // sphere: in addition to to_world
    double radius = 1.0;       // sphere
    std::string material;      // key into SceneDesc::materials
    std::optional<EmitterDesc> emitter;
    bool flip_normals = false;
    bool face_normals = false;       // mesh: ignore the file's vertex normals
    bool drop_degenerate = true;     // mesh: skip zero-area triangles (with a warning) instead of failing
    bool flip_tex_coords = true;     // mesh: v' = 1 - v (Mitsuba's default for OBJ and PLY)
    // mesh: only these of the file's meshes, as Assimp numbers them (glTF: each primitive of each
    // mesh in order), wherever the file's nodes place them; empty = all. The glTF importer gives
    // each material its own shape this way while the geometry stays in the file.
    std::vector<int> mesh_parts;
    SourceLoc loc;
    std::string written;  // mesh: the file as the scene wrote it, for messages
    SourceLoc file_loc;   // mesh: of the file value itself
};

enum class LightType { Point, Spot, Directional, Constant, EnvMap };

struct LightDesc {
    LightType type = LightType::Point;
    Vec3d position{0, 0, 0};        // point
    Rgb intensity{1.f, 1.f, 1.f};   // point, spot: W/sr
    Mat4 to_world;                  // spot: looks along local +z
    float cutoff_angle = 20.f;      // spot, degrees
    float beam_width = 15.f;        // spot, degrees (default 3/4 of cutoff)
    Vec3d direction{0, 0, -1};      // directional: direction of travel
    Rgb irradiance{1.f, 1.f, 1.f};  // directional: W/m^2 on a plane facing it
    Rgb radiance{1.f, 1.f, 1.f};    // constant environment: W/(m^2 sr)
    // envmap: an equirectangular image (light/envmap.h) in radiance units, times `scale`;
    // to_world (above) orients it.
    std::string file;      // absolute path
    std::string written;   // as the scene wrote it, for messages
    SourceLoc file_loc;    // of the file value itself
    float scale = 1.f;
    SourceLoc loc;
};

struct SceneDesc {
    std::string path;  // the scene file, for messages and relative paths
    IntegratorDesc integrator;
    SensorDesc sensor;
    std::map<std::string, MaterialDesc> materials;
    std::vector<ShapeDesc> shapes;
    std::vector<LightDesc> lights;
    std::vector<std::string> warnings;  // things the parser accepted but wants the user to know
    // Who may open what: every file the scene names is checked through it at parse time and
    // read through it by Scene::build. Null: FileGate::unconfined().
    std::shared_ptr<const FileGate> files;
};

}  // namespace omega
