#version 450
// Warped Julia sets on the sphere: lat-long and cube environment maps. The shader is julia_body.glsl.
#extension GL_GOOGLE_include_directive : require
#define K_ENVMAP 1
#include "julia_body.glsl"
