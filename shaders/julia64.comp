#version 450
// Warped Julia sets with the grid and orbits in double (a layer's "precision": "double"; devices
// with shaderFloat64). The shader is julia_body.glsl.
#extension GL_GOOGLE_include_directive : require
#define K_JULIA_F64 1
#define K_F64       1 /* kernels/exact.h's kx_ddiv */
#include "julia_body.glsl"
