/*
 * Bracketed L-systems (D0L, optionally stochastic): rules, presets, parallel rewriting with a bound
 * on the string's length, and the turtle that turns the derived string into line segments.
 */
#ifndef FB_LSYS_H
#define FB_LSYS_H

#include "fb.h"

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#define FB_LSYS_MAX_RULES 32
#define FB_LSYS_MAX_SUCC  1000 /* symbols in one successor or the axiom */
#define FB_LSYS_PRESETS   "bush|tree|sticks|weed|stochastic"

/* One production pred -> succ, chosen with probability p among the productions of pred (p < 0: not
 * given; a symbol with one production takes it always, with several they share equally). */
typedef struct fb_lsys_rule {
    char pred;
    double p;
    char succ[FB_LSYS_MAX_SUCC + 1];
} fb_lsys_rule;

typedef struct fb_lsys {
    char axiom[FB_LSYS_MAX_SUCC + 1];
    int nrules;
    fb_lsys_rule rules[FB_LSYS_MAX_RULES];
    int iterations;
    double angle; /* degrees turned by + and - */
} fb_lsys;

/* A preset by name (FB_LSYS_PRESETS): axiom, rules, iterations and angle. */
fb_result fb_lsys_preset(const char *name, fb_lsys *out);

/* Parses "X=successor", "X->successor" or, stochastic, "X(0.33)=successor" into *out (whitespace
 * is dropped from the successor). On a problem: false and the reason in msg. */
bool fb_lsys_parse_rule(const char *text, fb_lsys_rule *out, char *msg, size_t n);

/* Checks a system: the axiom and every successor bracket-balanced, '[' and ']' never rewritten,
 * each symbol's probabilities all given or all missing, positive and summing to 1 (within 1e-6).
 * On a problem: false, *bad the rule at fault (-1: the axiom or the system) and the reason in msg. */
bool fb_lsys_valid(const fb_lsys *ls, int *bad, char *msg, size_t n);

/* Rewrites the axiom `iterations` times in parallel. Stochastic productions are chosen by a hash of
 * (seed, iteration, position), so a derivation is a pure function of the seed. Each string's length
 * is counted before it is allocated: fails with FB_ERR_INPUT, naming `who` and the iteration, when a
 * string would exceed max_symbols symbols, when two strings would not fit in fb_memory_limit(mem), or
 * (max_f > 0) when the last would hold more than max_f F symbols. On success *out is a malloc'd
 * NUL-terminated string of *len symbols. */
fb_result fb_lsys_derive(const fb_lsys *ls, uint32_t seed, uint64_t max_symbols, uint64_t max_f, const fb_memory *mem,
                         const char *who, char **out, size_t *len);

/* One drawn segment, in the turtle's units. */
typedef struct fb_lsys_seg {
    double x0, y0, x1, y1;
    int depth; /* bracket nesting depth where it was drawn */
} fb_lsys_seg;

/* The turtle: F draws a segment of length `step` along the heading, f moves without drawing, + and
 * - turn by +angle and -angle (counter-clockwise positive, y up), | turns by 180 degrees, [ pushes
 * and ] pops the state (position, heading, depth); other symbols are ignored. The start is the
 * origin, heading `heading` degrees (90: up). Returns the segments (malloc'd) in string order and the
 * deepest segment's depth. Errors name `who`. */
fb_result fb_lsys_turtle(const char *s, size_t len, double angle, double heading, double step, const char *who,
                         fb_lsys_seg **segs, size_t *nsegs, int *max_depth);

#endif
