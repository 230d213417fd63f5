#version 450
// The chaos game with 32-bit atomics (any device). The shader is ifs_body.glsl.
#extension GL_GOOGLE_include_directive : require
#include "ifs_body.glsl"
