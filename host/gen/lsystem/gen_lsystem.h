/*
 * The lsystem generator's parameters (a layer's, as parsed from the scene) and its class.
 */
#ifndef FB_GEN_LSYSTEM_H
#define FB_GEN_LSYSTEM_H

#include "gen.h"
#include "lsys.h"
#include "palette.h"

typedef struct fb_lsystem_params {
    fb_lsys sys;    /* axiom, rules, iterations, angle */
    double heading; /* degrees; 90: up */
    double step;    /* segment length, turtle units */
    double width;   /* branch width at depth 0, in steps */
    double taper;   /* width factor per bracket depth */
    uint64_t max_symbols;
    bool auto_bounds;
    double bounds[4];
    fb_palette_spec palette; /* colour by depth: 0 at the trunk, 1 at the deepest branches */
} fb_lsystem_params;

extern const fb_gen_class fb_gen_lsystem;

/* The L-system of `obj` (an lsystem layer, or an ifs layer's condensation set): a preset fills in what
 * the object does not give, and the stored scene then spells it out; keys checked against `keys`, which
 * fill their fields of `params`, then the L-system `ls` they filled is checked. */
fb_result fb_lsystem_parse_def(const fb_vctx *v, const char *path, json_t *obj, const fb_keyspec *keys, int nkeys,
                               const char *what, void *params, const fb_lsys *ls);

/* The rules key's value: its reader fills the rules of the fb_lsys that is its field. */
extern const fb_kvalue fb_lsystem_rules_value;

/* A production "X=successor" or "X(p)=successor" (the rules key's check). */
bool fb_lsystem_check_rule(const char *text, char *msg, size_t size);

#endif
