// Transforms in the scene format (`to_world`): one operation or a list of them, applied in
// Mitsuba's order, refused when singular or not affine.
#include <cmath>
#include <initializer_list>
#include <utility>
#include <vector>

#include "scene/scene_parser.h"

namespace omega {

namespace {

Mat4 transform_op(const std::string& op, const ParamValue& v) {
    if (op == "matrix") {
        if (!v.is_list() || v.node().size() != 16) v.fail("expected 16 numbers (row-major), got " + v.describe());
        auto items = v.as_list();
        Mat4 m;
        for (size_t i = 0; i < 16; ++i) m.m[i] = items[i].as_double();
        return m;
    }
    if (op == "look_at") {
        ParamBag b(v);
        Vec3d origin = b.require("origin").as_vec3();
        Vec3d target = b.require("target").as_vec3();
        Vec3d up = b.require("up").as_vec3();
        b.check_unused();
        Vec3d dir = target - origin;
        if (length(dir) == 0 || !std::isfinite(length(dir))) v.fail("origin and target must differ");
        Vec3d l = cross(normalize(up), normalize(dir));
        if (!(length(l) > 1e-9)) v.fail("up must not be zero or parallel to the view direction");
        return Mat4::look_at(origin, target, up);
    }
    if (op == "translate") return Mat4::translate(v.as_vec3());
    if (op == "rotate") {
        ParamBag b(v);
        ParamValue axis_v = b.require("axis");
        Vec3d axis = axis_v.as_vec3();
        double angle = b.require("angle").as_double();
        b.check_unused();
        if (!(length(axis) > 0) || !std::isfinite(length(axis))) axis_v.fail("axis must be a non-zero vector");
        return Mat4::rotate(axis, angle);
    }
    // scale: a number or a vector
    if (v.is_scalar()) {
        double s = v.as_double();
        return Mat4::scale({s, s, s});
    }
    if (!v.is_list()) v.fail("expected a number or [x, y, z], got " + v.describe());
    return Mat4::scale(v.as_vec3());
}

const std::initializer_list<const char*> kTransformOps = {"matrix", "look_at", "translate", "rotate", "scale"};

// A mapping holding exactly one transform operation.
Mat4 single_op(const ParamValue& v) {
    ParamBag b(v);
    std::vector<std::pair<std::string, ParamValue>> ops;
    for (const char* op : kTransformOps)
        if (auto x = b.get(op)) ops.emplace_back(op, *x);
    b.check_unused();
    if (ops.size() != 1)
        v.fail("expected exactly one of matrix, look_at, translate, rotate, scale (use a list to combine them)");
    return transform_op(ops[0].first, ops[0].second);
}

}  // namespace

Mat4 parse_to_world(const ParamValue& v) {
    Mat4 m;
    if (v.is_list()) {
        // Mitsuba order: the first operation applies to the points first, so it is the rightmost.
        for (const ParamValue& item : v.as_list()) m = single_op(item) * m;
    } else if (v.is_map()) {
        m = single_op(v);
    } else {
        v.fail("expected a transform mapping or a list of them, got " + v.describe());
    }
    if (!m.is_finite()) v.fail("matrix is not finite");
    if (m(3, 0) != 0 || m(3, 1) != 0 || m(3, 2) != 0 || m(3, 3) != 1)
        v.fail("last row must be [0, 0, 0, 1] (an affine transform)");
    double s = 0;
    for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 3; ++c) s = std::max(s, std::abs(m(r, c)));
    double det = m.det3();
    // Relative test: the cornell-box matrices have 1e-8 entries that are harmless, a zero scale is not.
    if (s == 0 || !(std::abs(det) > 1e-12 * s * s * s) || !m.inverse()) v.fail("matrix is singular");
    return m;
}

}  // namespace omega
