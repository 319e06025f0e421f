// Maths written once for every lane width: the convention of the generators that define a
// function both for one ray (scalars and float3) and for the CPU lanes' vectors (cpu/simd.h's
// vfloat, one ray a lane, and cpu/shade_lanes.h's LaneVec), and the float3 operations they use.
//
// A generator DEFINE_..._MATHS(Q, f, F, I, U, V, v) defines its functions with the qualifier Q
// (inline, or LANES_INLINE) and the prefix f (empty for one ray: `surface_point`; lanes_ for
// the lanes: `lanes_surface_point`), for floats F, masks I (a comparison's type: scalar ones
// give 1, vector ones -1; select() takes either, and the bodies combine masks with & | and !,
// never ~), unsigned integers U, and 3-vectors V with fields x, y, z whose operations are
// named v##_make, v##_splat, v##_add, v##_sub, v##_mul, v##_scale, v##_div, v##_neg, v##_abs,
// v##_max, v##_select, v##_dot, v##_cross, v##_length, v##_positive, v##_any and
// v##_offset_step (f3_* below, f3_offset_step in traverse.h; the lanes' lv_*). The generators are DEFINE_SAMPLING_MATHS (rng.h), DEFINE_RAY_MATHS (F and
// I only) and DEFINE_SURFACE_MATHS (traverse.h), DEFINE_LAMBERT_MATHS (lambert.h),
// DEFINE_TRIANGLE_LIGHT_MATHS (lights.h) and DEFINE_VERTEX_MATHS (path.h, with its own naming).
//
// Both forms must compute the same bits: each body is one operation per expression in the
// order the scalar form has always computed it. The OpenCL C compiler fuses a scalar product
// into a sum where contraction is on (before traverse.h's `#pragma OPENCL FP_CONTRACT OFF`)
// but not a vector one, so a body compiled there writes each fused product as fma() and has no
// product next to a sum elsewhere.
#ifndef SHARED_VEC3_H
#define SHARED_VEC3_H

inline float3 f3_make(float x, float y, float z) { return (float3)(x, y, z); }
inline float3 f3_splat(float s) { return (float3)(s); }
inline float3 f3_add(float3 a, float3 b) { return a + b; }
inline float3 f3_sub(float3 a, float3 b) { return a - b; }
inline float3 f3_mul(float3 a, float3 b) { return a * b; }
inline float3 f3_scale(float3 a, float s) { return a * s; }
inline float3 f3_div(float3 a, float s) { return a / s; }
inline float3 f3_neg(float3 a) { return -a; }
inline float3 f3_abs(float3 a) { return fabs(a); }
inline float3 f3_max(float3 a, float3 b) { return fmax(a, b); }
inline float3 f3_select(float3 a, float3 b, int m) { return m ? b : a; }
inline float f3_dot(float3 a, float3 b) { return dot(a, b); }
inline float3 f3_cross(float3 a, float3 b) { return cross(a, b); }
inline float f3_length(float3 a) { return length(a); }
inline int f3_positive(float3 a) { return a.x > 0.0f || a.y > 0.0f || a.z > 0.0f; }
inline bool f3_any(int m) { return m != 0; }

#endif  // SHARED_VEC3_H
