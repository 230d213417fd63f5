/*
 * Adaptive exact orient2d and incircle (see predicates.h). The floating-point filters and their
 * error bounds are Shewchuk's ("Adaptive Precision Floating-Point Arithmetic and Fast Robust
 * Geometric Predicates", 1997); the exact fallbacks are written here with his expansion
 * operations (two-sum, Dekker's two-product, zero-eliminating expansion sums and scaling).
 *
 * An expansion is an array of doubles, increasing in magnitude, non-overlapping, whose exact sum
 * is the value; its sign is the sign of its last (largest) component.
 */
#include "predicates.h"

#include <math.h>

#define EPS      0x1p-53     /* half an ulp of 1 */
#define SPLITTER 134217729.0 /* 2^27 + 1 */

static const double ccw_bound = (3.0 + 16.0 * EPS) * EPS;
static const double icc_bound = (10.0 + 96.0 * EPS) * EPS;

static _Thread_local unsigned long long n_orient_exact, n_incircle_exact;

void fb_predicates_counts(unsigned long long *orient_exact, unsigned long long *incircle_exact)
{
    *orient_exact = n_orient_exact;
    *incircle_exact = n_incircle_exact;
}

/* ---- error-free transformations ------------------------------------------------------------- */

static inline void two_sum(double a, double b, double *x, double *y)
{
    double s = a + b, bv = s - a, av = s - bv;
    *x = s;
    *y = (a - av) + (b - bv);
}

static inline void two_diff(double a, double b, double *x, double *y)
{
    double s = a - b, bv = a - s, av = s + bv;
    *x = s;
    *y = (a - av) + (bv - b);
}

static inline void split(double a, double *hi, double *lo)
{
    double c = SPLITTER * a, big = c - a;
    *hi = c - big;
    *lo = a - *hi;
}

static inline void two_product(double a, double b, double *x, double *y)
{
    double p = a * b, ah, al, bh, bl;
    split(a, &ah, &al);
    split(b, &bh, &bl);
    double e1 = p - ah * bh, e2 = e1 - al * bh, e3 = e2 - ah * bl;
    *x = p;
    *y = al * bl - e3;
}

/* ---- expansions ------------------------------------------------------------------------------ */

/* h = e + f (Shewchuk's fast_expansion_sum_zeroelim; needs round-to-nearest-even). h holds
 * elen + flen components at most. Returns the length of h (0 for an exact zero). */
static int exp_sum(int elen, const double *e, int flen, const double *f, double *h)
{
    if (!elen) {
        for (int i = 0; i < flen; i++) h[i] = f[i];
        return flen;
    }
    if (!flen) {
        for (int i = 0; i < elen; i++) h[i] = e[i];
        return elen;
    }
    double q, qn, hh, en = e[0], fn = f[0];
    int ei = 0, fi = 0, hi = 0;
    if ((fn > en) == (fn > -en)) {
        q = en;
        en = ++ei < elen ? e[ei] : 0;
    } else {
        q = fn;
        fn = ++fi < flen ? f[fi] : 0;
    }
    if (ei < elen && fi < flen) {
        if ((fn > en) == (fn > -en)) {
            double s = en + q, bv = s - en;
            hh = q - bv, qn = s;
            en = ++ei < elen ? e[ei] : 0;
        } else {
            double s = fn + q, bv = s - fn;
            hh = q - bv, qn = s;
            fn = ++fi < flen ? f[fi] : 0;
        }
        q = qn;
        if (hh != 0) h[hi++] = hh;
        while (ei < elen && fi < flen) {
            if ((fn > en) == (fn > -en)) {
                two_sum(q, en, &qn, &hh);
                en = ++ei < elen ? e[ei] : 0;
            } else {
                two_sum(q, fn, &qn, &hh);
                fn = ++fi < flen ? f[fi] : 0;
            }
            q = qn;
            if (hh != 0) h[hi++] = hh;
        }
    }
    while (ei < elen) {
        two_sum(q, en, &qn, &hh);
        en = ++ei < elen ? e[ei] : 0;
        q = qn;
        if (hh != 0) h[hi++] = hh;
    }
    while (fi < flen) {
        two_sum(q, fn, &qn, &hh);
        fn = ++fi < flen ? f[fi] : 0;
        q = qn;
        if (hh != 0) h[hi++] = hh;
    }
    if (q != 0 || hi == 0) h[hi++] = q;
    return hi == 1 && h[0] == 0 ? 0 : hi;
}

/* h = b * e (Shewchuk's scale_expansion_zeroelim). h holds 2 * elen components at most. */
static int exp_scale(int elen, const double *e, double b, double *h)
{
    if (!elen || b == 0) return 0;
    double q, hh, p1, p0, s;
    int hi = 0;
    two_product(e[0], b, &q, &hh);
    if (hh != 0) h[hi++] = hh;
    for (int i = 1; i < elen; i++) {
        two_product(e[i], b, &p1, &p0);
        two_sum(q, p0, &s, &hh);
        if (hh != 0) h[hi++] = hh;
        two_sum(p1, s, &q, &hh);
        if (hh != 0) h[hi++] = hh;
    }
    if (q != 0 || hi == 0) h[hi++] = q;
    return hi == 1 && h[0] == 0 ? 0 : hi;
}

/* h = e * f; h holds 2 * elen * flen components at most, tmp twice that. */
static int exp_mul(int elen, const double *e, int flen, const double *f, double *h, double *tmp)
{
    int hlen = 0;
    double part[2 * 64];
    for (int i = 0; i < flen; i++) {
        int plen = exp_scale(elen, e, f[i], part);
        int n = exp_sum(hlen, h, plen, part, tmp);
        for (int k = 0; k < n; k++) h[k] = tmp[k];
        hlen = n;
    }
    return hlen;
}

static double exp_sign_value(int n, const double *e)
{
    return n ? e[n - 1] : 0.0;
}

/* The 2x2 determinant a * d - b * c as an expansion of at most 4 components. */
static int det2(double a, double d, double b, double c, double *h)
{
    double x[2], y[2];
    two_product(a, d, &x[1], &x[0]);
    two_product(-b, c, &y[1], &y[0]);
    return exp_sum(2, x, 2, y, h);
}

/* ---- orient2d --------------------------------------------------------------------------------- */

double fb_orient2d_exact(const double *a, const double *b, const double *c)
{
    /* ax by - ax cy - ay bx + ay cx + bx cy - by cx, summed exactly. */
    double t1[4], t2[4], t3[4], s12[8], s[12];
    int n1 = det2(a[0], b[1], a[1], b[0], t1); /* ax by - ay bx */
    int n2 = det2(b[0], c[1], b[1], c[0], t2); /* bx cy - by cx */
    int n3 = det2(c[0], a[1], c[1], a[0], t3); /* cx ay - cy ax */
    int n12 = exp_sum(n1, t1, n2, t2, s12);
    int n = exp_sum(n12, s12, n3, t3, s);
    return exp_sign_value(n, s);
}

double fb_orient2d(const double *a, const double *b, const double *c)
{
    double l = (a[0] - c[0]) * (b[1] - c[1]), r = (a[1] - c[1]) * (b[0] - c[0]), det = l - r;
    double sum;
    if (l > 0) {
        if (r <= 0) return det;
        sum = l + r;
    } else if (l < 0) {
        if (r >= 0) return det;
        sum = -l - r;
    } else {
        return det;
    }
    if (det >= ccw_bound * sum || -det >= ccw_bound * sum) return det;
    n_orient_exact++;
    return fb_orient2d_exact(a, b, c);
}

/* ---- incircle ----------------------------------------------------------------------------------- */

/* lift * minor, summed into acc (at most 2 * 4 * mlen more components). */
static int add_lifted(int alen, double *acc, const double *p, int mlen, const double *minor, double sign, double *out)
{
    double lift[4], xx[2], yy[2], prod[2 * 4 * 12], tmp[2 * 2 * 4 * 12];
    two_product(p[0], p[0], &xx[1], &xx[0]);
    two_product(p[1], p[1], &yy[1], &yy[0]);
    int llen = exp_sum(2, xx, 2, yy, lift);
    for (int i = 0; i < llen; i++) lift[i] *= sign;
    int plen = exp_mul(mlen, minor, llen, lift, prod, tmp);
    return exp_sum(alen, acc, plen, prod, out);
}

/* The exact 4x4 determinant |x y x^2+y^2 1| over rows a, b, c, d, expanded along the lifted column:
 * + |a|^2 O(b,c,d) - |b|^2 O(a,c,d) + |c|^2 O(a,b,d) - |d|^2 O(a,b,c), with O the orientation
 * determinant |x y 1|. Equal to the translated 3x3 incircle determinant. */
double fb_incircle_exact(const double *a, const double *b, const double *c, const double *d)
{
    const double *pts[4] = {a, b, c, d};
    double acc[2][400];
    int alen = 0, cur = 0;
    for (int i = 0; i < 4; i++) {
        const double *q[3];
        int k = 0;
        for (int j = 0; j < 4; j++)
            if (j != i) q[k++] = pts[j];
        double t1[4], t2[4], t3[4], s12[8], m[12];
        int n1 = det2(q[0][0], q[1][1], q[0][1], q[1][0], t1);
        int n2 = det2(q[1][0], q[2][1], q[1][1], q[2][0], t2);
        int n3 = det2(q[2][0], q[0][1], q[2][1], q[0][0], t3);
        int n12 = exp_sum(n1, t1, n2, t2, s12);
        int mlen = exp_sum(n12, s12, n3, t3, m);
        alen = add_lifted(alen, acc[cur], pts[i], mlen, m, (i & 1) ? -1.0 : 1.0, acc[cur ^ 1]);
        cur ^= 1;
    }
    return exp_sign_value(alen, acc[cur]);
}

/* When the translated coordinates are exact (their two-diff tails are zero, as on grids), the
 * translated 3x3 determinant is evaluated exactly with shorter expansions. */
static double incircle_translated_exact(double adx, double ady, double bdx, double bdy, double cdx, double cdy)
{
    double bc[4], ca[4], ab[4], al[4], bl[4], cl[4], x[2], y[2];
    double p1[32], p2[32], p3[32], s12[64], s[96], tmp[64];
    int nbc = det2(bdx, cdy, cdx, bdy, bc);
    int nca = det2(cdx, ady, adx, cdy, ca);
    int nab = det2(adx, bdy, bdx, ady, ab);
    two_product(adx, adx, &x[1], &x[0]);
    two_product(ady, ady, &y[1], &y[0]);
    int nal = exp_sum(2, x, 2, y, al);
    two_product(bdx, bdx, &x[1], &x[0]);
    two_product(bdy, bdy, &y[1], &y[0]);
    int nbl = exp_sum(2, x, 2, y, bl);
    two_product(cdx, cdx, &x[1], &x[0]);
    two_product(cdy, cdy, &y[1], &y[0]);
    int ncl = exp_sum(2, x, 2, y, cl);
    int n1 = exp_mul(nbc, bc, nal, al, p1, tmp);
    int n2 = exp_mul(nca, ca, nbl, bl, p2, tmp);
    int n3 = exp_mul(nab, ab, ncl, cl, p3, tmp);
    int n12 = exp_sum(n1, p1, n2, p2, s12);
    int n = exp_sum(n12, s12, n3, p3, s);
    return exp_sign_value(n, s);
}

double fb_incircle(const double *a, const double *b, const double *c, const double *d)
{
    double adx = a[0] - d[0], bdx = b[0] - d[0], cdx = c[0] - d[0];
    double ady = a[1] - d[1], bdy = b[1] - d[1], cdy = c[1] - d[1];
    double bdxcdy = bdx * cdy, cdxbdy = cdx * bdy, alift = adx * adx + ady * ady;
    double cdxady = cdx * ady, adxcdy = adx * cdy, blift = bdx * bdx + bdy * bdy;
    double adxbdy = adx * bdy, bdxady = bdx * ady, clift = cdx * cdx + cdy * cdy;
    double det = alift * (bdxcdy - cdxbdy) + blift * (cdxady - adxcdy) + clift * (adxbdy - bdxady);
    double perm = (fabs(bdxcdy) + fabs(cdxbdy)) * alift + (fabs(cdxady) + fabs(adxcdy)) * blift +
                  (fabs(adxbdy) + fabs(bdxady)) * clift;
    double bound = icc_bound * perm;
    if (det > bound || -det > bound) return det;
    n_incircle_exact++;
    double t;
    int exact = 1;
    two_diff(a[0], d[0], &adx, &t), exact &= t == 0;
    two_diff(b[0], d[0], &bdx, &t), exact &= t == 0;
    two_diff(c[0], d[0], &cdx, &t), exact &= t == 0;
    two_diff(a[1], d[1], &ady, &t), exact &= t == 0;
    two_diff(b[1], d[1], &bdy, &t), exact &= t == 0;
    two_diff(c[1], d[1], &cdy, &t), exact &= t == 0;
    if (exact) return incircle_translated_exact(adx, ady, bdx, bdy, cdx, cdy);
    return fb_incircle_exact(a, b, c, d);
}
