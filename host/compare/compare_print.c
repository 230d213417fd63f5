/* compare's report as lines or as one JSON object (compare_int.h). */
#include "compare_int.h"

#include "jsonout.h"

#include <stdarg.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static json_t *cmp_idiff_json(const cmp *k);

void cmp_say(const fb_compare_desc *d, const char *fmt, ...)
{
    if (d->json) return; /* the JSON object carries the same */
    char buf[1024];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(buf, sizeof buf, fmt, ap);
    va_end(ap);
    d->print(buf, d->user);
}

const char *cmp_verdict_name(fb_verdict v)
{
    return v == FB_VERDICT_PASS ? "pass" : v == FB_VERDICT_WARN ? "warn" : "fail";
}

static void add_limit(json_t *o, const char *key, bool has, double v)
{
    if (has) json_object_set_new(o, key, json_real(v));
}

static json_t *json_num(double v)
{
    return isfinite(v) ? json_real(v) : json_null();
}

static json_t *channel_json(const cmp *k, const chan_stats *c)
{
    json_t *j = json_object(), *lim = json_object();
    json_object_set_new(j, "name", json_string(c->name));
    json_object_set_new(j, "result", json_string(cmp_verdict_name(c->verdict)));
    if (c->why[0]) json_object_set_new(j, "reason", json_string(c->why));
    json_object_set_new(j, "max_abs", json_num(c->max_abs));
    if (c->max_x >= 0) json_object_set_new(j, "max_at", json_pack("[ii]", c->max_x, c->max_y));
    json_object_set_new(j, "rmse", json_num(c->rmse));
    json_object_set_new(j, "psnr_db", json_num(c->psnr));
    json_object_set_new(j, "beyond_fail_pixels", json_integer((json_int_t)c->beyond));
    json_object_set_new(j, "beyond_fail_percent", json_real(c->pct));
    if (c->has_warn) json_object_set_new(j, "beyond_warn_percent", json_real(c->wpct));
    if (c->has_ssim) json_object_set_new(j, "ssim", json_real(c->ssim_v));
    json_object_set_new(j, "nonfinite_differ", json_integer((json_int_t)c->nonfinite_mismatch));
    add_limit(lim, "fail", c->abs_test, c->fail);
    add_limit(lim, "failpercent", c->abs_test, c->failpct);
    add_limit(lim, "hardfail", c->has_hardfail, c->hardfail);
    add_limit(lim, "warn", c->has_warn, c->warn);
    add_limit(lim, "warnpercent", c->has_warn, c->warnpct);
    add_limit(lim, "hardwarn", c->has_hardwarn, c->hardwarn);
    add_limit(lim, "rmse", c->has_rmse, c->rmse_max);
    add_limit(lim, "psnr", c->has_psnr, c->psnr_min);
    add_limit(lim, "ssim", c->has_ssim, c->ssim_min);
    json_object_set_new(j, "thresholds", lim);
    (void)k;
    return j;
}

double cmp_flip_stat(const flip_unit *u, int stat)
{
    const double v[] = {u->r.mean, u->r.median, u->r.q1, u->r.q3, u->r.max};
    return v[stat >= 0 && stat < 5 ? stat : 0];
}

static json_t *flip_json(const cmp *k, const flip_unit *u)
{
    json_t *j = json_pack("{sssssssfsfsfsfsfsf}", "name", u->name, "mode", u->hdr ? "HDR" : "LDR", "result",
                          cmp_verdict_name(u->verdict), "mean", u->r.mean, "weighted_median", u->r.median,
                          "weighted_q1", u->r.q1, "weighted_q3", u->r.q3, "min", u->r.min, "max", u->r.max);
    json_object_set_new(j, "channels", json_string(u->grey ? "Y" : "R,G,B"));
    if (u->hdr) {
        json_object_set_new(j, "start_exposure", json_real(u->r.start_exposure));
        json_object_set_new(j, "stop_exposure", json_real(u->r.stop_exposure));
        json_object_set_new(j, "num_exposures", json_integer(u->r.nexp));
        json_object_set_new(j, "zero_median", json_boolean(u->r.zero_median));
    }
    json_object_set_new(j, "nonfinite_differ", json_integer((json_int_t)u->nonfinite));
    if (u->why[0]) json_object_set_new(j, "reason", json_string(u->why));
    json_t *lim = json_object();
    add_limit(lim, "flip_fail", u->has_fail, u->limit_fail);
    add_limit(lim, "flip_warn", u->has_warn, u->limit_warn);
    if (u->has_fail || u->has_warn) json_object_set_new(lim, "statistic", json_string(CMP_FLIP_STATS[k->d->flip_stat]));
    json_object_set_new(j, "thresholds", lim);
    return j;
}

/* The end of the report: the verdict line, or the JSON object. */
void cmp_print_result(const cmp *k)
{
    const fb_compare_desc *d = k->d;
    if (!d->json) {
        char line[600];
        snprintf(line, sizeof line, "result: %s%s%s",
                 k->verdict == FB_VERDICT_PASS   ? "PASS"
                 : k->verdict == FB_VERDICT_WARN ? "WARN"
                                                 : "FAIL",
                 k->reason[0] ? ": " : "", k->reason);
        d->print(line, d->user);
        return;
    }
    json_t *o = json_object(), *chans = json_array();
    json_object_set_new(o, "a", json_string(d->a));
    json_object_set_new(o, "b", json_string(d->b));
    if (k->W > 0) json_object_set_new(o, "size", json_pack("[ii]", k->W, k->H));
    json_object_set_new(o, "result", json_string(cmp_verdict_name(k->verdict)));
    if (k->reason[0]) json_object_set_new(o, "reason", json_string(k->reason));
    for (int s = 0; s < k->nst; s++) json_array_append_new(chans, channel_json(k, &k->st[s]));
    json_object_set_new(o, "channels", chans);
    if (d->flip) {
        json_t *f = json_array();
        for (int u = 0; u < k->nfu; u++) json_array_append_new(f, flip_json(k, &k->fu[u]));
        json_object_set_new(o, "flip", f);
    }
    if (k->over) json_object_set_new(o, "idiff", cmp_idiff_json(k));
    if (k->missing && json_array_size(k->missing)) json_object_set(o, "missing", k->missing);
    char *text = fb_json_dumps(o, 0);
    d->print(text ? text : "{}", d->user);
    free(text);
    json_decref(o);
}

void cmp_channel_lines(const cmp *k, const chan_stats *c)
{
    const fb_compare_desc *d = k->d;
    char where[64] = "", ss[32] = "";
    if (c->max_x >= 0) snprintf(where, sizeof where, " at pixel (%d, %d)", c->max_x, c->max_y);
    if (c->has_ssim) snprintf(ss, sizeof ss, "  ssim %.6f", c->ssim_v);
    cmp_say(d, "%-16s max_abs %.6g%s  rmse %.6g  psnr %s%.2f dB  beyond %.4f%% (%llu px)%s  %s", c->name, c->max_abs,
            where, c->rmse, c->psnr > 0 && isinf(c->psnr) ? "+" : "", c->psnr, c->pct, (unsigned long long)c->beyond,
            ss,
            c->verdict == FB_VERDICT_PASS   ? "ok"
            : c->verdict == FB_VERDICT_WARN ? "WARN"
                                            : "FAIL");
    if (c->verdict != FB_VERDICT_PASS) cmp_say(d, "%-16s %s", "", c->why);
    if (c->nonfinite_mismatch || c->nonfinite_same)
        cmp_say(d,
                "%-16s non-finite pixels: %llu differ between the files (each a failing pixel; RMSE, PSNR and SSIM "
                "at their worst), %llu identical in both",
                "", (unsigned long long)c->nonfinite_mismatch, (unsigned long long)c->nonfinite_same);
    if (c->n && c->a_lo == 0 && c->a_hi == 0) cmp_say(d, "%-16s all-zero in %s", "", d->a);
}

/* idiff's mean and RMS error and peak SNR; a non-finite value in one file only makes them inf, inf
 * and -inf, the worst each can be (as RMSE and PSNR per channel) */
static void idiff_numbers(const cmp *k, double *mean, double *rms, double *psnr)
{
    *mean = k->i_nvals ? k->i_sum / (double)k->i_nvals : 0;
    *rms = k->i_nvals ? sqrt(k->i_sq / (double)k->i_nvals) : 0;
    *psnr = *rms > 0 ? 20 * log10(k->i_peak / *rms) : INFINITY;
    if (k->i_nonfinite) *mean = *rms = INFINITY, *psnr = -INFINITY;
}

/* --idiff-stats: idiff's block, its numbers by its definitions. */
void cmp_idiff_lines(const cmp *k)
{
    const fb_compare_desc *d = k->d;
    double npels = (double)k->W * k->H, mean, rms, psnr;
    idiff_numbers(k, &mean, &rms, &psnr);
    cmp_say(d, "idiff statistics over the %d compared channels:", k->nst);
    cmp_say(d, "  Mean error = %.6g", mean);
    cmp_say(d, "  RMS error = %.6g", rms);
    cmp_say(d, "  Peak SNR = %.6g", psnr);
    cmp_say(d, "  Max error  = %.6g @ (%d, %d, %s)", k->i_max, k->i_mx, k->i_my, k->i_mc ? k->i_mc : "-");
    cmp_say(d, "  %llu pixels (%.3g%%) over %g", (unsigned long long)k->i_nwarn, npels ? 100 * k->i_nwarn / npels : 0,
            k->i_warn);
    cmp_say(d, "  %llu pixels (%.3g%%) over %g", (unsigned long long)k->i_nfail, npels ? 100 * k->i_nfail / npels : 0,
            k->i_fail);
    if (k->i_nonfinite)
        cmp_say(d, "  %llu values non-finite in one file only: each over both thresholds, the errors at their worst",
                (unsigned long long)k->i_nonfinite);
}

static json_t *cmp_idiff_json(const cmp *k)
{
    double npels = (double)k->W * k->H, mean, rms, psnr;
    idiff_numbers(k, &mean, &rms, &psnr);
    json_t *j = json_object();
    json_object_set_new(j, "mean_error", json_num(mean));
    json_object_set_new(j, "rms_error", json_num(rms));
    json_object_set_new(j, "peak_snr", json_num(psnr));
    json_object_set_new(j, "peak", json_real(k->i_peak));
    json_object_set_new(j, "max_error", json_num(k->i_max));
    if (k->i_mc) json_object_set_new(j, "max_at", json_pack("[iis]", k->i_mx, k->i_my, k->i_mc));
    json_object_set_new(j, "nonfinite_differ", json_integer((json_int_t)k->i_nonfinite));
    json_object_set_new(j, "warn_pixels", json_integer((json_int_t)k->i_nwarn));
    json_object_set_new(j, "warn_percent", json_real(npels ? 100 * k->i_nwarn / npels : 0));
    json_object_set_new(j, "warn_threshold", json_real(k->i_warn));
    json_object_set_new(j, "fail_pixels", json_integer((json_int_t)k->i_nfail));
    json_object_set_new(j, "fail_percent", json_real(npels ? 100 * k->i_nfail / npels : 0));
    json_object_set_new(j, "fail_threshold", json_real(k->i_fail));
    return j;
}
