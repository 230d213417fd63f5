// Warped Julia sets: one invocation per two neighbouring pixels of a row, their orbits iterated in
// one loop (two dependency chains in flight) on a CPU device, one after the other on a GPU
// (kernels/device.h). The math is kernels/julia.h. Included by julia.comp
// (float), julia_env.comp (K_ENVMAP: float, lat-long and cube maps) and julia64.comp (K_JULIA_F64:
// the grid and orbit in double; needs shaderFloat64).
#define K_GLSL 1
#include "../kernels/device.h"
#include "../kernels/julia.h"
#include "../kernels/palette.h"

layout(local_size_x = 64, local_size_y = 1, local_size_z = 1) in;

// The mapping, fixed per pipeline so that the compiler folds the other one away.
layout(constant_id = 0) const uint MAPPING = 0u;
// Turbulence on or off and the colour sample count, fixed per pipeline: code that cannot run is
// folded away (on lavapipe the unused turbulence fBm alone cost 4x).
layout(constant_id = 1) const uint TURBULENCE = 0u;
layout(constant_id = 2) const uint SAMPLES = 1u;
// bit 0: gamma != 1, bit 1: density > 0. A ternary on a buffer value compiles to a select that
// evaluates pow() whatever the value; known constants fold it away.
layout(constant_id = 3) const uint COLOUR_FLAGS = 3u;
// bit k: the layer stores channel k of iter, n, inside, de, R, G, B. What no stored channel needs
// is not computed; a buffer not stored is bound but never written.
layout(constant_id = 4) const uint OUTPUTS = 127u;
// 1: the image width is even, so every invocation's two pixels are a whole, aligned vec2 of each
// plane (i = row * width + x is even) and go out in one store: llvmpipe stores to a storage buffer
// lane by lane, each lane behind an exec-mask branch, so a pair's store is one lane loop where two
// stores were two (the same bits either way). 0: each pixel on its own.
layout(constant_id = 5) const uint EVEN_WIDTH = 0u;

layout(push_constant) uniform Push
{
    K_JuliaParams p;
    uint y0;   // first image row of this strip
    uint rows; // rows in this strip
}
pc;

// Each plane as pairs: pixel i is v[i / 2][i % 2], the same bytes as a plain array of 32-bit values.
layout(std430, set = 0, binding = 0) writeonly buffer Iter { uvec2 v[]; } o_iter;
layout(std430, set = 0, binding = 1) writeonly buffer Smooth { vec2 v[]; } o_n;
layout(std430, set = 0, binding = 2) writeonly buffer Inside { vec2 v[]; } o_inside;
layout(std430, set = 0, binding = 3) writeonly buffer De { vec2 v[]; } o_de;
layout(std430, set = 0, binding = 4) writeonly buffer Red { vec2 v[]; } o_r;
layout(std430, set = 0, binding = 5) writeonly buffer Green { vec2 v[]; } o_g;
layout(std430, set = 0, binding = 6) writeonly buffer Blue { vec2 v[]; } o_b;
// A uniform buffer: lavapipe gathers the palette entries that each lane indexes, where from a storage
// buffer it loads them lane by lane and component by component behind two branches each. std140
// gives the host's std430 offsets here: turb's 84 bytes round up to 96, so the entries still start
// at 144 (host/gen/julia/layer.c, julia_palette, without its pad).
layout(std140, set = 0, binding = 7) uniform Palette
{
    K_SkyColour colour;
    K_FbmParams turb;
    vec4 entries[K_PALETTE_SIZE];
#ifdef K_JULIA_F64
    K_JuliaD dp; // the double parameters and constants
#endif
}
pal;

// The palette lookup of kernels/palette.h (k_sky_rgb), the entries fetched from the buffer.
vec3 sky_colour(K_JuliaResult res)
{
    K_SkyColour c = pal.colour;
    if ((COLOUR_FLAGS & 1u) == 0u) c.gamma = 1.0f;
    if ((COLOUR_FLAGS & 2u) == 0u) c.density = 0.0f;
    uint i0 = k_sky_i0(c, res.nsmooth);
    return k_sky_rgb(c, res.inside, res.nsmooth, pal.entries[i0], pal.entries[k_sky_i1(i0)]);
}

#ifndef K_JULIA_F64
// Sample k of pixels (x, y) and (x + 1, y) (has_b false: the first only). On a CPU device the two
// orbits share one loop: two dependency chains a SIMD lane. On a GPU one runs after the other: a
// warp runs a loop as long as its slowest lane, so the pair's loop lasted as long as the slowest of
// 64 pixels, each loop now as long as the slowest of 32. The results are k_julia_run's either way.
K_JuliaPair sample2(K_JuliaParams p, uint x, uint y, uint k, bool has_b, uint want)
{
    if (K_CPU_DEVICE) return k_julia_sample2(p, pal.turb, pal.colour.seed, x, y, k, has_b, want);
    K_JuliaPair r;
    k_vec2 fa = k_julia_sample_xy(p, pal.colour.seed, x, y, k);
    r.a = k_julia_run(p, k_julia_start_at(p, pal.turb, fa.x, fa.y), want);
    r.b = r.a;
    if (has_b) {
        k_vec2 fb = k_julia_sample_xy(p, pal.colour.seed, x + 1u, y, k);
        r.b = k_julia_run(p, k_julia_start_at(p, pal.turb, fb.x, fb.y), want);
    }
    return r;
}
#endif

// Pixel i alone.
void store(uint i, K_JuliaResult res)
{
    uint h = i >> 1u, c = i & 1u;
    if ((OUTPUTS & 1u) != 0u) o_iter.v[h][c] = res.iter;
    if ((OUTPUTS & 2u) != 0u) o_n.v[h][c] = res.nsmooth;
    if ((OUTPUTS & 4u) != 0u) o_inside.v[h][c] = float(res.inside);
    if ((OUTPUTS & 8u) != 0u) o_de.v[h][c] = res.de;
}

// Pixels i and i + 1, i even (EVEN_WIDTH).
void store2(uint i, K_JuliaResult a, K_JuliaResult b)
{
    uint h = i >> 1u;
    if ((OUTPUTS & 1u) != 0u) o_iter.v[h] = uvec2(a.iter, b.iter);
    if ((OUTPUTS & 2u) != 0u) o_n.v[h] = vec2(a.nsmooth, b.nsmooth);
    if ((OUTPUTS & 4u) != 0u) o_inside.v[h] = vec2(float(a.inside), float(b.inside));
    if ((OUTPUTS & 8u) != 0u) o_de.v[h] = vec2(a.de, b.de);
}

vec3 mean_colour(vec3 sum)
{
    float s = pal.colour.inv_samples;
    return SAMPLES == 1u ? sum : vec3(sum.r * s, sum.g * s, sum.b * s);
}

void store_colour(uint i, vec3 sum)
{
    uint h = i >> 1u, c = i & 1u;
    vec3 m = mean_colour(sum);
    o_r.v[h][c] = m.r;
    o_g.v[h][c] = m.g;
    o_b.v[h][c] = m.b;
}

void store_colour2(uint i, vec3 sa, vec3 sb)
{
    uint h = i >> 1u;
    vec3 a = mean_colour(sa), b = mean_colour(sb);
    o_r.v[h] = vec2(a.r, b.r);
    o_g.v[h] = vec2(a.g, b.g);
    o_b.v[h] = vec2(a.b, b.b);
}

void main()
{
    uint x = 2u * gl_GlobalInvocationID.x;
    uint r = gl_GlobalInvocationID.y;
    if (x >= pc.p.width || r >= pc.rows) return;
    K_JuliaParams p = pc.p;
    p.mapping = MAPPING;
    if (TURBULENCE == 0u) p.lambda = 0.0f;
    uint want = ((OUTPUTS & 0x72u) != 0u ? K_JULIA_WANT_SMOOTH : 0u) | ((OUTPUTS & 8u) != 0u ? K_JULIA_WANT_DE : 0u);
    bool has_b = x + 1u < p.width;
    uint y = pc.y0 + r;
#ifdef K_JULIA_F64
    // double precision: the two pixels one after the other
    K_JuliaPair res;
    res.a = k_julia_run_d(p, pal.dp, pal.turb, double(x) + 0.5, double(y) + 0.5, want);
    res.b = res.a;
    if (has_b) res.b = k_julia_run_d(p, pal.dp, pal.turb, double(x) + 1.5, double(y) + 0.5, want);
#else
    K_JuliaPair res = sample2(p, x, y, 0u, has_b, want);
#endif
    uint i = r * p.width + x;
    if (EVEN_WIDTH != 0u) {
        store2(i, res.a, res.b);
    } else {
        store(i, res.a);
        if (has_b) store(i + 1u, res.b);
    }
    if ((OUTPUTS & 0x70u) == 0u) return;
    // Colour: the average of `samples` jittered samples in linear colour (sample 0 is the centre).
    vec3 sa = sky_colour(res.a), sb = sky_colour(res.b);
    for (uint k = 1u; k < SAMPLES; k++) {
#ifdef K_JULIA_F64
        K_JuliaPair q;
        k_vec2 fa = k_julia_sample_xy(p, pal.colour.seed, x, y, k);
        q.a = k_julia_run_d(p, pal.dp, pal.turb, double(fa.x), double(fa.y), K_JULIA_WANT_SMOOTH);
        q.b = q.a;
        if (has_b) {
            k_vec2 fb = k_julia_sample_xy(p, pal.colour.seed, x + 1u, y, k);
            q.b = k_julia_run_d(p, pal.dp, pal.turb, double(fb.x), double(fb.y), K_JULIA_WANT_SMOOTH);
        }
#else
        K_JuliaPair q = sample2(p, x, y, k, has_b, K_JULIA_WANT_SMOOTH);
#endif
        sa += sky_colour(q.a);
        sb += sky_colour(q.b);
    }
    if (EVEN_WIDTH != 0u) {
        store_colour2(i, sa, sb);
    } else {
        store_colour(i, sa);
        if (has_b) store_colour(i + 1u, sb);
    }
}
