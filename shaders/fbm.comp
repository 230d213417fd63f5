#version 450
// fBm noise on the plane. The shader is fbm_body.glsl.
#extension GL_GOOGLE_include_directive : require
#include "fbm_body.glsl"
