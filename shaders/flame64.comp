#version 450
// The flame's chaos game with 64-bit atomics, two fields an add, or an opaque genome's four
// (VK_KHR_shader_atomic_int64).
#extension GL_GOOGLE_include_directive : require
#extension GL_EXT_shader_explicit_arithmetic_types_int64 : require
#extension GL_EXT_shader_atomic_int64 : require
#define FB_FLAME_INT64 1
#include "flame_body.glsl"
