#pragma once
// Four lanes of float and of their bits (GCC and Clang vector extensions; SSE2 on x86-64), for
// the few per-hit routines that do the same arithmetic on x, y and z. Lane-wise IEEE operations
// round exactly as the scalar ones, so results stay bit for bit those of the scalar code; the
// fourth lane is padding.
#include <cstdint>

#include "math/vec.h"

namespace omega {

using F4 = float __attribute__((vector_size(16)));
using U4 = uint32_t __attribute__((vector_size(16)));
using I4 = int32_t __attribute__((vector_size(16)));

inline F4 to_f4(const Vec3& v) { return F4{v.x, v.y, v.z, 0.f}; }
inline Vec3 to_vec3(F4 v) { return {v[0], v[1], v[2]}; }
// |v| by clearing the sign bits, as std::abs does per float.
inline F4 abs4(F4 v) { return (F4)((U4)v & 0x7fffffffu); }

}  // namespace omega
