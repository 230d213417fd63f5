#version 450
// The flame's chaos game with 32-bit atomics (any device). The shader is flame_body.glsl.
#extension GL_GOOGLE_include_directive : require
#include "flame_body.glsl"
