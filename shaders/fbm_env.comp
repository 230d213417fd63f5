#version 450
// fBm noise on the sphere: lat-long and cube environment maps (3D noise). The shader is fbm_body.glsl.
#extension GL_GOOGLE_include_directive : require
#define K_ENVMAP 1
#include "fbm_body.glsl"
