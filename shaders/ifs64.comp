#version 450
// The chaos game with one 64-bit atomic add per point (devices with VK_KHR_shader_atomic_int64).
#extension GL_GOOGLE_include_directive : require
#extension GL_EXT_shader_explicit_arithmetic_types_int64 : require
#extension GL_EXT_shader_atomic_int64 : require
#define FB_IFS_INT64 1
#include "ifs_body.glsl"
