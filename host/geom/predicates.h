/*
 * Robust geometric predicates in Shewchuk's manner: a floating-point evaluation with a forward
 * error bound decides the sign whenever it can, and an exact evaluation with floating-point
 * expansions (sums of non-overlapping doubles) decides it otherwise. The sign returned is always
 * the sign of the exact determinant of the double inputs.
 *
 * The expansion arithmetic needs IEEE double rounding without fused multiply-add contraction:
 * the project compiles with -ffp-contract=off.
 */
#ifndef FB_PREDICATES_H
#define FB_PREDICATES_H

/* > 0 if a, b, c turn counter-clockwise, < 0 clockwise, 0 collinear. The value is the determinant
 * (b - a) x (c - a) when the fast path decides, else a number of the same sign. */
double fb_orient2d(const double *a, const double *b, const double *c);

/* > 0 if d lies inside the circle through a, b, c (counter-clockwise), < 0 outside, 0 on it. */
double fb_incircle(const double *a, const double *b, const double *c, const double *d);

/* The exact evaluations alone (no filter), for tests. */
double fb_orient2d_exact(const double *a, const double *b, const double *c);
double fb_incircle_exact(const double *a, const double *b, const double *c, const double *d);

/* How often the filters failed since start (statistics for benchmarks and tests). */
void fb_predicates_counts(unsigned long long *orient_exact, unsigned long long *incircle_exact);

#endif
