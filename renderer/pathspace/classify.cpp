#include "pathspace/classify.h"

#include "pathspace/mirror_connector.h"

#include <algorithm>
#include <fmt/format.h>

namespace omega {

EndpointClass classify_light(const Light& light) {
    if (std::holds_alternative<PointLight>(light) || std::holds_alternative<SpotLight>(light)) return {'S', 'D'};
    if (std::holds_alternative<DirectionalLight>(light)) return {'D', 'S'};
    return {'D', 'D'};  // area lights and the environment (an area at infinity)
}

EndpointClass classify_sensor(const Sensor& sensor) {
    // Sensor letters read direction first: (S|D)(S|D)E.
    EndpointClass c;
    c.direction = sensor.delta_direction() ? 'S' : 'D';
    c.position = sensor.delta_position() ? 'S' : 'D';
    if (auto* tl = std::get_if<ThinLensSensor>(&sensor.model); tl && tl->aperture_radius <= 0) c.position = 'S';
    return c;
}

std::string PathClass::regex() const {
    std::string r = "L ";
    r += light.position;
    r += ' ';
    r += light.direction;
    for (char c : surfaces) {
        r += ' ';
        r += c == 'M' ? 'S' : c;
    }
    r += ' ';
    r += sensor.direction;
    r += ' ';
    r += sensor.position;
    r += " E";
    return r;
}

bool locally_sampleable(const PathClass& c) {
    // The endpoints' letters take part: L D D ... (an area light hit by a sensor subpath) and
    // ... D D E (a lens hit by a light subpath) are the DD edges to the imaginary vertices.
    std::string all;
    all += c.light.position;
    all += c.light.direction;
    all += c.surfaces;
    all += c.sensor.direction;
    all += c.sensor.position;
    return all.find("DD") != std::string::npos;
}

namespace {
// The class with every M read as S: what strategies without the connector see.
PathClass without_mirrors(PathClass c) {
    std::replace(c.surfaces.begin(), c.surfaces.end(), 'M', 'S');
    return c;
}
}  // namespace

bool sampleable_by(const PathClass& c, IntegratorType integrator) {
    const std::string& v = c.surfaces;
    const size_t n = v.size();
    if (v.find('M') != std::string::npos) {
        if (sampleable_by(without_mirrors(c), integrator)) return true;
        // The planar-mirror connector (pathspace/mirror_connector.h) joins the two vertices
        // around one M: a D surface, the light (sampled from the image: any light) or the sensor
        // (sampled from the image: any sensor); the light endpoint itself needs a position and a
        // direction density to be joined to the sensor (n = 1).
        const bool light_end_joinable = c.light.direction == 'D';
        auto joins = [&](size_t j) {
            if (v[j] != 'M') return false;
            if (n == 1) return light_end_joinable;
            return (j == 0 || v[j - 1] == 'D') && (j == n - 1 || v[j + 1] == 'D');
        };
        // Path tracer: next-event estimation from a D vertex through M to the light (s = 1).
        if (integrator == IntegratorType::Path) return n >= 2 && v[0] == 'M' && v[1] == 'D';
        // Light tracer, when the lens cannot be hit: through the last M to the sensor (t = 1).
        const bool lens_hittable = c.sensor.direction == 'D' && c.sensor.position == 'D';
        if (integrator == IntegratorType::Light) return !lens_hittable && joins(n - 1);
        // bdpt: the connector at any (s, t).
        for (size_t j = 0; j < n; ++j)
            if (joins(j)) return true;
        return false;
    }
    const bool hittable = c.light.position == 'D' && c.light.direction == 'D';
    // s = 0: the sensor subpath hits the light.
    const bool s0 = hittable;
    // s = 1: next-event estimation from the first surface vertex (any light: point, spot,
    // area by sampling, directional by projection).
    const bool s1 = n >= 1 && v[0] == 'D';
    // t = 1: light tracing to the sensor from the last surface vertex (any sensor: pinhole,
    // lens, orthographic by projection); with no surface, the light itself if it has a
    // position to connect (not a light at infinity) and a direction density.
    const bool t1 = n >= 1 ? v[n - 1] == 'D' : (c.light.direction == 'D' && c.sensor.direction == 'D');
    // s >= 2, t >= 2: an edge between two D surface vertices.
    const bool inner = v.find("DD") != std::string::npos;
    // t = 0: the light subpath hits a lens of finite aperture (D D E), whatever came before.
    const bool t0 = c.sensor.direction == 'D' && c.sensor.position == 'D';
    switch (integrator) {
        case IntegratorType::Path: return s0 || s1;
        case IntegratorType::Light: return t1;
        case IntegratorType::Bdpt: return s0 || s1 || t1 || inner || t0;
    }
    return false;
}

namespace {

std::string light_words(const Light& l) {
    if (std::holds_alternative<PointLight>(l)) return "a point light";
    if (std::holds_alternative<SpotLight>(l)) return "a spot light";
    if (std::holds_alternative<DirectionalLight>(l)) return "a directional light";
    if (is_environment(l)) return "the environment";
    return "an area light";
}

std::string sensor_words(const Sensor& s) {
    if (std::holds_alternative<OrthographicSensor>(s.model)) return "an orthographic camera";
    if (auto* tl = std::get_if<ThinLensSensor>(&s.model); tl && tl->aperture_radius > 0) return "a thin-lens camera";
    return "a pinhole camera";
}

const char* integrator_words(IntegratorType t) {
    switch (t) {
        case IntegratorType::Path: return "the path tracer";
        case IntegratorType::Light: return "the light tracer";
        case IntegratorType::Bdpt: return "bidirectional path tracing";
    }
    return "?";
}

std::string describe(const PathClass& mc, const std::string& light, const std::string& sensor) {
    const PathClass c = without_mirrors(mc);
    const std::string& v = c.surfaces;
    if (v.empty()) return light + " seen directly by " + sensor;
    const bool caustic = v[0] == 'S' && v.find('D') != std::string::npos;
    if (v.find('D') == std::string::npos) return light + " seen in mirrors/glass by " + sensor;
    if (v.back() == 'S')
        return caustic ? "caustics from " + light + " seen in mirrors/glass by " + sensor
                       : "light from " + light + " on diffuse surfaces seen in mirrors/glass by " + sensor;
    return caustic ? "caustics from " + light + " (light reaching diffuse surfaces through mirrors/glass) seen by " + sensor
                   : "diffuse interreflection of " + light + " seen by " + sensor;
}

}  // namespace

SceneClasses classify_scene(const Scene& scene) {
    SceneClasses sc;
    for (const Light& l : scene.lights()) {
        EndpointClass c = classify_light(l);
        std::string name = light_words(l);
        bool seen = false;
        for (size_t i = 0; i < sc.lights.size(); ++i)
            if (sc.light_names[i] == name) seen = true;
        if (!seen) {
            sc.lights.push_back(c);
            sc.light_names.push_back(name);
        }
        if (c.position == 'D' && c.direction == 'D') sc.any_light_hittable = true;
    }
    sc.sensor = classify_sensor(scene.sensor());
    sc.sensor_name = sensor_words(scene.sensor());
    // Per shape: a delta lobe on a connector mirror is M, anywhere else S.
    const PlanarMirrors mirrors = find_planar_mirrors(scene);
    for (uint32_t i = 0; i < scene.shapes().size(); ++i) {
        uint8_t lobes = bsdf_lobes(scene.materials()[scene.shapes()[i].material]);
        if (lobes & (kLobeDiffuse | kLobeGlossy)) sc.has_diffuse = true;
        if (lobes & kLobeDelta) (mirrors.index(i) >= 0 ? sc.has_planar_mirror : sc.has_specular) = true;
    }
    return sc;
}

std::vector<std::string> path_space_warnings(const Scene& scene, IntegratorType integrator) {
    SceneClasses sc = classify_scene(scene);
    std::string symbols;
    if (sc.has_specular) symbols += 'S';
    if (sc.has_planar_mirror) symbols += 'M';
    if (sc.has_diffuse) symbols += 'D';
    std::vector<std::string> out;
    // Enumerate surface sequences up to 3 bounces, shortest first, and report the unsampleable ones.
    std::vector<std::string> seqs{""};
    for (int len = 1; len <= 3; ++len) {
        std::vector<std::string> next;
        for (const auto& s : seqs)
            if (int(s.size()) == len - 1)
                for (char ch : symbols) next.push_back(s + ch);
        seqs.insert(seqs.end(), next.begin(), next.end());
    }
    std::vector<std::string> reported;
    for (size_t li = 0; li < sc.lights.size(); ++li) {
        for (const auto& seq : seqs) {
            PathClass c{sc.lights[li], seq, sc.sensor};
            bool any = locally_sampleable(c);
            bool ours = sampleable_by(c, integrator);
            if (ours) continue;
            // One warning per kind of effect: longer classes with the same description (more
            // mirror bounces, say) are the same family.
            std::string what = describe(c, sc.light_names[li], sc.sensor_name);
            if (std::find(reported.begin(), reported.end(), what) != reported.end()) continue;
            reported.push_back(what);
            // Which other integrator can, through a connector where no local strategy does.
            std::string other;
            for (IntegratorType t : {IntegratorType::Bdpt, IntegratorType::Path, IntegratorType::Light})
                if (t != integrator && other.empty() && sampleable_by(c, t)) other = integrator_words(t);
            if (!any && !other.empty())
                out.push_back(fmt::format("{} ({}): missing, no local path sampling strategy can produce these paths "
                                          "(Veach, Theorem 8.3: no DD edge), and {} has no connector for them; {} "
                                          "reaches them through its planar-mirror connector",
                                          c.regex(), what, integrator_words(integrator), other));
            else if (!any)
                out.push_back(fmt::format("{} ({}): missing, no local path sampling strategy can produce these paths "
                                          "(Veach, Theorem 8.3: no DD edge)",
                                          c.regex(), what));
            else if (!other.empty())
                out.push_back(fmt::format("{} ({}): missing, {} cannot sample these paths ({} can)", c.regex(), what,
                                          integrator_words(integrator), other == "bidirectional path tracing" ? "bdpt" : other));
            else  // a connector class that only another connector could reach
                out.push_back(fmt::format("{} ({}): missing, {} cannot sample these paths", c.regex(), what,
                                          integrator_words(integrator)));
            if (out.size() >= 6) return out;
        }
    }
    return out;
}

StrategyPlan plan_strategies(const Scene& scene) {
    SceneClasses sc = classify_scene(scene);
    StrategyPlan p;
    p.s0 = sc.any_light_hittable;
    // Every connection ends at a D surface vertex; without one only s = 0 remains.
    p.connections = sc.has_diffuse;
    p.t0 = scene.sensor().lens_hittable();
    p.light_subpaths = sc.has_diffuse || p.t0;
    return p;
}

}  // namespace omega
