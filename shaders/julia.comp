#version 450
// Warped Julia sets in float. The shader is julia_body.glsl.
#extension GL_GOOGLE_include_directive : require
#include "julia_body.glsl"
