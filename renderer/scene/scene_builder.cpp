// Resource loading: SceneDesc -> Scene. Only what the scene references is loaded; materials no
// shape uses are not built, and their textures are not read. Each image file is decoded once,
// however many materials name it.
#include <cmath>
#include <limits>
#include <map>
#include <stdexcept>
#include <unordered_map>

#include <fmt/format.h>

#include "scene/scene.h"
#include "io/file_gate.h"
#include "scene/scene_error.h"
#include "scene/scene_files.h"
#include "texture/image.h"

namespace omega {

namespace {

std::string where(const SourceLoc& loc) { return fmt::format("{}:{}", loc.file, loc.line); }

double triangle_area(const TriangleMesh& m, size_t t) {
    Vec3d p0(m.positions[m.indices[3 * t]]), p1(m.positions[m.indices[3 * t + 1]]), p2(m.positions[m.indices[3 * t + 2]]);
    return 0.5 * length(cross(p1 - p0, p2 - p0));
}

Light make_light(const LightDesc& d) {
    switch (d.type) {
        case LightType::Point: return PointLight{Vec3(d.position), d.intensity};
        case LightType::Spot: {
            auto tf = Transform::make(d.to_world);
            SpotLight s;
            s.position = Vec3(tf->point({0, 0, 0}));
            s.frame = Frame::from_normal(Vec3(normalize(tf->vector({0, 0, 1}))));
            s.intensity = d.intensity;
            s.cutoff_rad = d.cutoff_angle * kPi / 180.f;
            s.beam_rad = std::min(d.beam_width, d.cutoff_angle) * kPi / 180.f;
            s.cos_cutoff = std::cos(s.cutoff_rad);
            return s;
        }
        case LightType::Directional: return DirectionalLight{Vec3(normalize(d.direction)), d.irradiance};
        case LightType::Constant: return ConstantLight{d.radiance};
        case LightType::EnvMap: break;  // built by load_envmap: it reads a file
    }
    throw std::logic_error("unknown light type");
}

// Reads the envmap's image through the scene's gate (decode_image: OIIO never sees a path).
EnvMapLight load_envmap(const FileGate& gate, const LightDesc& d) {
    const SourceLoc& loc = d.file_loc.file.empty() ? d.loc : d.file_loc;
    const std::string where_ = loc.key.empty() ? fmt::format("{}: ", where(loc)) : fmt::format("{}: {}: ", where(loc), loc.key);
    ImagePixels px = decode_image(gate, d.file, d.written, where_, "envmap");
    const size_t nc = size_t(px.channels);
    std::vector<Rgb> rgb(size_t(px.width) * size_t(px.height));
    for (size_t i = 0; i < rgb.size(); ++i) {
        const float* p = &px.data[i * nc];
        rgb[i] = nc >= 3 ? Rgb{p[0], p[1], p[2]} : Rgb(p[0]);
    }
    try {
        return EnvMapLight{std::make_shared<const EnvMap>(px.width, px.height, std::move(rgb), d.scale, d.to_world)};
    } catch (const std::invalid_argument& e) {
        throw SceneError(fmt::format("{}envmap '{}': {}", where_, d.written.empty() ? d.file : d.written, e.what()));
    }
}

// Points model T's texture slot at `tex` and puts the texture's mean in the parameter, if `b`
// is a T. Returns whether it was.
template <class T>
bool attach(Bsdf& b, Rgb T::*value, const BitmapTexture* T::*slot, const BitmapTexture* tex) {
    auto* m = std::get_if<T>(&b);
    if (!m) return false;
    m->*slot = tex;
    m->*value = tex->mean();
    return true;
}

// The material's textures on its BSDF. The parser accepts each texture only on the models
// listed here, so a refusal means a hand-built SceneDesc, named all the same.
template <class TextureFor>
void attach_textures(const MaterialDesc& md, Bsdf& b, TextureFor&& texture_for) {
    auto refuse = [](const BitmapDesc& bd, const char* models) {
        throw SceneError(fmt::format("{}: {}: only {} take this texture", where(bd.loc), bd.loc.key, models));
    };
    if (const auto& bd = md.reflectance_texture) {
        const BitmapTexture* t = texture_for(*bd);
        if (!attach(b, &DiffuseBsdf::reflectance, &DiffuseBsdf::reflectance_tex, t) &&
            !attach(b, &PlasticBsdf::diffuse_reflectance, &PlasticBsdf::diffuse_reflectance_tex, t))
            refuse(*bd, "a diffuse or plastic reflectance");
    }
    if (const auto& bd = md.specular_texture) {
        const BitmapTexture* t = texture_for(*bd);
        if (!attach(b, &ConductorBsdf::specular_reflectance, &ConductorBsdf::specular_reflectance_tex, t) &&
            !attach(b, &DielectricBsdf::specular_reflectance, &DielectricBsdf::specular_reflectance_tex, t) &&
            !attach(b, &ThinDielectricBsdf::specular_reflectance, &ThinDielectricBsdf::specular_reflectance_tex, t) &&
            !attach(b, &PlasticBsdf::specular_reflectance, &PlasticBsdf::specular_reflectance_tex, t))
            refuse(*bd, "conductors, dielectrics and plastics");
    }
    if (const auto& bd = md.transmittance_texture) {
        const BitmapTexture* t = texture_for(*bd);
        if (!attach(b, &DielectricBsdf::specular_transmittance, &DielectricBsdf::specular_transmittance_tex, t) &&
            !attach(b, &ThinDielectricBsdf::specular_transmittance, &ThinDielectricBsdf::specular_transmittance_tex, t))
            refuse(*bd, "dielectrics");
    }
    if (const auto& bd = md.alpha_texture) {
        // The mean stands in where no hit is at hand (and decides the lobe class: glossy, since
        // a textured roughness is never below kMinTexturedAlpha).
        const BitmapTexture* t = texture_for(*bd);
        const Rgb mean = t->mean();
        if (auto* c = std::get_if<ConductorBsdf>(&b)) {
            c->alpha_tex = t;
            c->alpha_u = c->alpha_v = texel_alpha(mean);
        } else if (auto* d = std::get_if<DielectricBsdf>(&b)) {
            d->alpha_tex = t;
            d->alpha_u = d->alpha_v = texel_alpha(mean);
        } else if (auto* p = std::get_if<PlasticBsdf>(&b); p && p->alpha > 0) {
            p->alpha_tex = t;
            p->alpha = texel_alpha(mean);
        } else if (auto* r = std::get_if<DiffuseBsdf>(&b); r && r->alpha > 0) {
            r->alpha_tex = t;
            r->alpha = texel_alpha(mean, 0.f, std::numeric_limits<float>::infinity());
        } else {
            refuse(*bd, "rough conductors, dielectrics, plastics and diffuse surfaces");
        }
    }
}

}  // namespace

std::unique_ptr<Scene> Scene::build(const SceneDesc& desc, const std::function<bool()>& cancelled) {
    auto poll = [&] {
        if (cancelled && cancelled()) throw BuildCancelled();
    };
    const FileGate& gate = scene_gate(desc);
    std::unique_ptr<Scene> s(new Scene());
    s->desc_ = desc;
    s->sensor_ = Sensor::from_desc(desc.sensor);

    // Materials are built only if some shape references them.
    std::unordered_map<std::string, uint32_t> material_index;
    std::map<std::pair<std::string, bool>, std::shared_ptr<const Image>> images;  // (file, raw)
    auto texture_for = [&](const BitmapDesc& bd) -> const BitmapTexture* {
        auto tex = std::make_unique<BitmapTexture>();
        tex->to_uv = bd.to_uv;
        if (bd.checker) {  // procedural: no file
            tex->checker = true;
            tex->color0 = bd.color0;
            tex->color1 = bd.color1;
        } else {
            auto& img = images[{bd.file, bd.raw}];
            if (!img) {
                poll();
                const std::string at = fmt::format("{}: {}: ", where(bd.loc), bd.loc.key);
                // An embedded image is decoded from the bytes the scene file carried: no file to open.
                img = bd.embedded ? load_image_bytes(bd.embedded->bytes, bd.embedded->name, bd.raw, at)
                                  : load_image(gate, bd.file, bd.raw, at, bd.written);
            }
            tex->image = img;
            tex->filter = bd.filter;
            tex->wrap = bd.wrap;
        }
        s->textures_.push_back(std::move(tex));
        return s->textures_.back().get();
    };
    auto material_for = [&](const ShapeDesc& sd, size_t i) -> uint32_t {
        auto it = material_index.find(sd.material);
        if (it != material_index.end()) return it->second;
        auto m = desc.materials.find(sd.material);
        if (m == desc.materials.end())
            throw SceneError(fmt::format("{}: shapes[{}].material: unknown material '{}'", where(sd.loc), i, sd.material));
        uint32_t idx = uint32_t(s->materials_.size());
        Bsdf b = m->second.bsdf;
        attach_textures(m->second, b, texture_for);
        s->materials_.push_back(b);
        material_index.emplace(sd.material, idx);
        return idx;
    };
    // Mask opacity and bump map per material (index as materials_), made once per material.
    struct ShapeTextures {
        float opacity = 1.f;
        const BitmapTexture* opacity_tex = nullptr;
        const BitmapTexture* bump_tex = nullptr;
        float bump_scale = 1.f;
    };
    std::vector<ShapeTextures> shape_tex;
    auto shape_textures_for = [&](uint32_t material, const std::string& name) {
        if (shape_tex.size() <= material) {
            const MaterialDesc& md = desc.materials.at(name);
            shape_tex.resize(material + 1);
            ShapeTextures& t = shape_tex[material];
            t.opacity = md.opacity;
            if (md.opacity_texture) t.opacity_tex = texture_for(*md.opacity_texture);
            if (md.bump_texture) t.bump_tex = texture_for(*md.bump_texture);
            t.bump_scale = md.bump_scale;
        }
        return shape_tex[material];
    };
    auto textured = [&](uint32_t material) {
        const ShapeTextures& t = shape_tex[material];
        return bsdf_is_textured(s->materials_[material]) || t.opacity < 1.f || t.opacity_tex || t.bump_tex;
    };

    s->shapes_.reserve(desc.shapes.size());
    for (size_t i = 0; i < desc.shapes.size(); ++i) {
        const ShapeDesc& sd = desc.shapes[i];
        poll();
        Shape sh;
        sh.name = fmt::format("shapes[{}]", i);
        sh.material = material_for(sd, i);
        {
            const ShapeTextures& t = shape_textures_for(sh.material, sd.material);
            sh.opacity = t.opacity;
            sh.opacity_tex = t.opacity_tex;
            sh.bump_tex = t.bump_tex;
            sh.bump_scale = t.bump_scale;
        }
        sh.flip_normals = sd.flip_normals;
        if (sd.type == ShapeType::Sphere) {
            if (sh.masked() || sh.bump_tex)
                throw SceneError(fmt::format("{}: {}: a mask (opacity) or bump map on a sphere is not supported; use a mesh",
                                             where(sd.loc), sh.name));
            sh.kind = ShapeKind::Sphere;
            // A sphere's to_world may translate and scale uniformly; anything else is rejected.
            Vec3d c = sd.to_world.point(sd.center);
            Vec3d ax = sd.to_world.vector({sd.radius, 0, 0}), ay = sd.to_world.vector({0, sd.radius, 0}),
                  az = sd.to_world.vector({0, 0, sd.radius});
            double r = length(ax);
            if (std::abs(length(ay) - r) > 1e-6 * r || std::abs(length(az) - r) > 1e-6 * r)
                throw SceneError(fmt::format("{}: {}.to_world: a sphere needs a uniform scale", where(sd.loc), sh.name));
            if (!(r > 0) || !std::isfinite(r))
                throw SceneError(fmt::format("{}: {}.radius: must be positive and finite", where(sd.loc), sh.name));
            sh.sphere = {c, r};
            sh.area = 4.0 * kPiD * r * r;
            if (textured(sh.material)) {
                sh.uv_map = UvMap::Sphere;
                sh.sphere_axes[0] = Vec3(normalize(ax));
                sh.sphere_axes[1] = Vec3(normalize(ay));
                sh.sphere_axes[2] = Vec3(normalize(az));
            }
        } else {
            sh.kind = ShapeKind::Triangles;
            switch (sd.type) {
                case ShapeType::Mesh:
                    sh.mesh = load_mesh_file(gate, sd.file, sd.file_loc.file.empty() ? sd.loc : sd.file_loc,
                                             MeshFileOptions{sd.flip_tex_coords, sd.written, cancelled, {}, sd.mesh_parts});
                    break;
                case ShapeType::Rectangle: sh.mesh = make_rectangle(); break;
                case ShapeType::Cube: sh.mesh = make_cube(); break;
                case ShapeType::Disk: sh.mesh = make_disk(); break;
                case ShapeType::Sphere: break;
            }
            // The rectangle, cube and disk are flat per triangle: their vertex normals are the face
            // normals, so interpolating them per hit (and normalizing) would only add rounding.
            if (sd.face_normals || sd.type != ShapeType::Mesh) sh.mesh.normals.clear();
            if (sh.bump_tex && sd.type == ShapeType::Disk)
                throw SceneError(fmt::format("{}: {}: a bump map on a disk is not supported; use a mesh", where(sd.loc), sh.name));
            if (textured(sh.material)) sh.uv_map = sd.type == ShapeType::Disk ? UvMap::Disk : UvMap::Vertex;
            else sh.mesh.uvs.clear();  // nothing looks them up
            auto tf = Transform::make(sd.to_world);
            if (!tf) throw SceneError(fmt::format("{}: {}.to_world: matrix is singular", where(sd.loc), sh.name));
            // "'DoorHandle' (door.obj)": the location's key already says shapes[i] in messages.
            std::string label;
            if (!sd.name.empty()) label = fmt::format("'{}'", sd.name);
            if (sd.type == ShapeType::Mesh)
                label += fmt::format("{}({})", label.empty() ? "" : " ", sd.written.empty() ? sd.file : sd.written);
            const std::string key = sd.loc.key.empty() ? sh.name : sd.loc.key;
            const std::string what = sd.loc.key.empty() ? key + (label.empty() ? "" : " " + label) : label;
            const size_t dropped = bake_mesh(sh.mesh, *tf, sd.flip_normals, sd.drop_degenerate, sd.loc, what);
            if (dropped)
                s->warnings_.push_back(fmt::format("{}: {}{}: {} degenerate (zero-area) triangle{} dropped",
                                                   where(sd.loc), key, label.empty() ? "" : " " + label, dropped,
                                                   dropped == 1 ? "" : "s"));
            std::vector<double> areas(sh.mesh.triangle_count());
            sh.face_normals.resize(areas.size());
            for (size_t t = 0; t < areas.size(); ++t) {
                areas[t] = triangle_area(sh.mesh, t);
                const auto& m = sh.mesh;
                Vec3d p0(m.positions[m.indices[3 * t]]), p1(m.positions[m.indices[3 * t + 1]]),
                    p2(m.positions[m.indices[3 * t + 2]]);
                Vec3 n(normalize(cross(p1 - p0, p2 - p0)));
                sh.face_normals[t] = n;  // bake_mesh already reversed the winding for flip_normals
            }
            sh.tri_by_area = DiscreteDistribution(areas);
            sh.area = sh.tri_by_area.total();
            if (sh.mesh.triangle_count() == 0)
                throw SceneError(fmt::format("{}: {}: the shape has no triangles", where(sd.loc), sh.name));
        }
        if (sd.emitter && !is_black(sd.emitter->radiance) && sh.masked())
            // Light sampling picks points by area, holes included: the emission would not match.
            throw SceneError(fmt::format("{}: {}: a mask (opacity) on an emitting shape is not supported", where(sd.loc),
                                         sh.name));
        if (sd.emitter && !is_black(sd.emitter->radiance)) {
            if (sh.kind == ShapeKind::Triangles) sh.parallelogram = find_parallelogram(sh.mesh);
            if (sh.kind == ShapeKind::Triangles && !sd.emitter->two_sided)
                sh.emitter_plane = find_emitter_plane(sh.mesh, sh.face_normals);
            sh.light = int32_t(s->lights_.size());
            s->lights_.push_back(AreaLight{uint32_t(i), sd.emitter->radiance, sd.emitter->two_sided});
        }
        sh.inv_area = float(1.0 / sh.area);
        s->shapes_.push_back(std::move(sh));
    }
    for (const LightDesc& ld : desc.lights) {
        if (ld.type == LightType::EnvMap) poll();
        Light l = ld.type == LightType::EnvMap ? Light(load_envmap(gate, ld)) : make_light(ld);
        // A light that emits nothing cannot contribute: leave it out.
        if (is_environment(l)) {
            if (auto* c = std::get_if<ConstantLight>(&l); c && is_black(c->radiance)) continue;
            if (auto* e = std::get_if<EnvMapLight>(&l); e && e->map->black()) continue;
            if (s->env_light_ >= 0)
                throw SceneError(fmt::format("{}: lights: only one environment (constant or envmap) is allowed", where(ld.loc)));
            s->env_light_ = int(s->lights_.size());
        }
        s->lights_.push_back(l);
    }

    poll();
    s->add_embree_geometry(cancelled);

    // A far clipping plane that cuts nothing changes nothing; one that would is not honoured.
    if (const SensorDesc& sd = desc.sensor; std::isfinite(sd.far_clip) && s->bounds_.lo.x <= s->bounds_.hi.x) {
        const Vec3d eye = sd.to_world.point({0, 0, 0}), axis = normalize(sd.to_world.vector({0, 0, 1}));
        double farthest = 0;
        for (int c = 0; c < 8; ++c) {
            const Vec3d corner((c & 1 ? s->bounds_.hi : s->bounds_.lo).x, (c & 2 ? s->bounds_.hi : s->bounds_.lo).y,
                               (c & 4 ? s->bounds_.hi : s->bounds_.lo).z);
            farthest = std::max(farthest, dot(corner - eye, axis));
        }
        if (farthest > sd.far_clip)
            s->warnings_.push_back(fmt::format(
                "{}: sensor.far_clip: geometry lies up to {:.4g} along the view axis, beyond far_clip {:.4g}; Omega "
                "does not clip far away, so it renders what a clipping renderer would hide",
                where(sd.loc), farthest, sd.far_clip));
    }

    std::vector<double> power;
    for (const Light& l : s->lights_) power.push_back(light_power(*s, l));
    s->light_select_ = DiscreteDistribution(power);
    return s;
}

void Scene::add_embree_geometry(const std::function<bool()>& cancelled) {
    device_ = rtcNewDevice(nullptr);
    if (!device_) throw std::runtime_error("embree: cannot create a device");
    rtc_ = rtcNewScene(device_);
    rtcSetSceneFlags(rtc_, RTC_SCENE_FLAG_CONTEXT_FILTER_FUNCTION);
    rtcSetSceneBuildQuality(rtc_, RTC_BUILD_QUALITY_HIGH);
    for (size_t i = 0; i < shapes_.size(); ++i) {
        Shape& sh = shapes_[i];
        if (sh.kind == ShapeKind::Sphere) {
            attach_sphere(device_, rtc_, unsigned(i), &sh.sphere);
            Vec3 c(sh.sphere.center);
            float r = float(sh.sphere.radius);
            bounds_.lo = vmin(bounds_.lo, c - Vec3(r));
            bounds_.hi = vmax(bounds_.hi, c + Vec3(r));
            continue;
        }
        RTCGeometry g = rtcNewGeometry(device_, RTC_GEOMETRY_TYPE_TRIANGLE);
        auto* v = static_cast<float*>(rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3,
                                                              3 * sizeof(float), sh.mesh.positions.size()));
        for (size_t k = 0; k < sh.mesh.positions.size(); ++k) {
            const Vec3& p = sh.mesh.positions[k];
            v[3 * k] = p.x; v[3 * k + 1] = p.y; v[3 * k + 2] = p.z;
            bounds_.lo = vmin(bounds_.lo, p);
            bounds_.hi = vmax(bounds_.hi, p);
        }
        auto* idx = static_cast<unsigned*>(rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                                                                   3 * sizeof(unsigned), sh.mesh.triangle_count()));
        std::copy(sh.mesh.indices.begin(), sh.mesh.indices.end(), idx);
        if (sh.masked()) attach_mask_filter(g, sh);
        rtcCommitGeometry(g);
        rtcAttachGeometryByID(rtc_, g, unsigned(i));
        rtcReleaseGeometry(g);
    }
    if (cancelled) {
        // Embree calls this from its build threads; returning false abandons the build.
        rtcSetSceneProgressMonitorFunction(
            rtc_, [](void* ptr, double) { return !(*static_cast<const std::function<bool()>*>(ptr))(); },
            const_cast<std::function<bool()>*>(&cancelled));
    }
    rtcCommitScene(rtc_);
    if (cancelled && cancelled()) throw BuildCancelled();
    if (rtcGetDeviceError(device_) != RTC_ERROR_NONE) throw std::runtime_error("embree: scene build failed");
    if (cancelled) rtcSetSceneProgressMonitorFunction(rtc_, nullptr, nullptr);
}

}  // namespace omega
