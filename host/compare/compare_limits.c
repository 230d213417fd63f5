/* compare's thresholds (compare.h): parsing, the rule that applies to a channel, every rule used. */
#include "compare_int.h"

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* ---- thresholds ------------------------------------------------------------------------------ */

static bool parse_value(const char *s, size_t n, double *out)
{
    char buf[64], *end;
    if (n == 0 || n >= sizeof buf) return false;
    memcpy(buf, s, n);
    buf[n] = 0;
    errno = 0;
    *out = strtod(buf, &end);
    return !*end && errno == 0 && isfinite(*out) && *out >= 0;
}

fb_result fb_limit_parse(const char *flag, const char *text, fb_limit *l)
{
    l->flag = flag;
    const char *p = text;
    bool seen_all = false;
    if (!*p) return fb_fail(FB_ERR_USAGE, "%s: missing value", flag);
    while (*p) {
        const char *end = strchr(p, ',');
        size_t n = end ? (size_t)(end - p) : strlen(p);
        const char *eq = memchr(p, '=', n);
        double v;
        if (!eq) {
            if (!parse_value(p, n, &v))
                return fb_fail(FB_ERR_USAGE, "%s: expected a finite number >= 0 or CHANNEL=VALUE, found \"%.*s\"", flag,
                               (int)n, p);
            if (seen_all)
                return fb_fail(FB_ERR_USAGE,
                               "%s: two values for every channel in \"%s\"; give one, and CHANNEL=VALUE or LAYER=VALUE "
                               "for the others",
                               flag, text);
            seen_all = true;
            l->has_all = true, l->all = v;
        } else {
            size_t kn = (size_t)(eq - p);
            if (kn == 0 || kn >= sizeof l->name[0] || !parse_value(eq + 1, n - kn - 1, &v))
                return fb_fail(FB_ERR_USAGE,
                               "%s: expected CHANNEL=VALUE (sky.R=1e-3) or LAYER=VALUE with a finite value >= 0, "
                               "found \"%.*s\"",
                               flag, (int)n, p);
            if (l->n >= FB_LIMIT_RULES)
                return fb_fail(FB_ERR_USAGE, "%s: at most %d CHANNEL=VALUE rules", flag, FB_LIMIT_RULES);
            memcpy(l->name[l->n], p, kn);
            l->name[l->n][kn] = 0;
            l->v[l->n++] = v;
        }
        l->set = true;
        p = end ? end + 1 : p + n;
        if (end && !*p) return fb_fail(FB_ERR_USAGE, "%s: a trailing comma in \"%s\"", flag, text);
    }
    return FB_OK;
}

/* 2: the rule names the channel; 1: its layer; 0: neither */
int cmp_rule_match(const char *rule, const char *channel)
{
    if (!strcmp(rule, channel)) return 2;
    size_t n = strlen(rule);
    return !strncmp(channel, rule, n) && channel[n] == '.' ? 1 : 0;
}

bool fb_limit_get(const fb_limit *l, const char *channel, double *v)
{
    int best = 0;
    for (int i = 0; i < l->n; i++) {
        int m = cmp_rule_match(l->name[i], channel);
        if (m > best) best = m, *v = l->v[i];
    }
    if (best) return true;
    if (l->has_all) *v = l->all;
    return l->has_all;
}

static fb_result rule_names_none(const fb_limit *l, int i, const char *const *names, int n)
{
    char list[512] = "";
    for (int s = 0; s < n && strlen(list) < 400; s++)
        snprintf(list + strlen(list), sizeof list - strlen(list), "%s%s", s ? ", " : "", names[s]);
    return fb_fail(FB_ERR_USAGE, "%s %s=...: no compared %s is %s or in layer %s (compared: %s)", l->flag, l->name[i],
                   l->flag && strstr(l->flag, "flip") ? "FLIP layer" : "channel", l->name[i], l->name[i],
                   list[0] ? list : "none");
}

/* Every CHANNEL=VALUE rule of every threshold must name a compared channel or layer (and a FLIP
 * rule a FLIP layer): a typo would otherwise leave a channel unchecked. */
fb_result cmp_check_rules(const cmp *c)
{
    const fb_compare_desc *d = c->d;
    const fb_limit *all[] = {&d->fail,     &d->failpercent, &d->hardfail, &d->warn, &d->warnpercent,
                             &d->hardwarn, &d->rmse,        &d->psnr,     &d->ssim};
    const char **names = calloc((size_t)(c->nst + c->nfu) + 1, sizeof *names);
    if (!names) return fb_fail(FB_ERR_NOMEM, "out of memory");
    for (int s = 0; s < c->nst; s++) names[s] = c->st[s].name;
    for (int u = 0; u < c->nfu; u++) names[c->nst + u] = c->fu[u].name;
    fb_result rc = FB_OK;
    for (size_t k = 0; k < sizeof all / sizeof all[0] && !rc; k++)
        for (int i = 0; i < all[k]->n && !rc; i++) {
            bool hit = false;
            for (int s = 0; s < c->nst && !hit; s++) hit = cmp_rule_match(all[k]->name[i], names[s]) > 0;
            if (!hit) rc = rule_names_none(all[k], i, names, c->nst);
        }
    const fb_limit *fl[] = {&d->flip_fail, &d->flip_warn};
    for (size_t k = 0; k < 2 && !rc; k++)
        for (int i = 0; i < fl[k]->n && !rc; i++) {
            bool hit = false;
            for (int u = 0; u < c->nfu && !hit; u++) hit = !strcmp(fl[k]->name[i], c->fu[u].name);
            if (!hit) rc = rule_names_none(fl[k], i, names + c->nst, c->nfu);
        }
    free(names);
    return rc;
}

/* A channel's thresholds from the limits. */
void cmp_thresholds(const fb_compare_desc *d, chan_stats *c)
{
    const char *n = c->name;
    c->has_rmse = fb_limit_get(&d->rmse, n, &c->rmse_max);
    c->has_psnr = fb_limit_get(&d->psnr, n, &c->psnr_min);
    c->has_ssim = fb_limit_get(&d->ssim, n, &c->ssim_min);
    bool has_fail = fb_limit_get(&d->fail, n, &c->fail);
    bool has_failpct = fb_limit_get(&d->failpercent, n, &c->failpct);
    c->has_hardfail = fb_limit_get(&d->hardfail, n, &c->hardfail);
    c->has_warn = fb_limit_get(&d->warn, n, &c->warn);
    c->has_warnpct = fb_limit_get(&d->warnpercent, n, &c->warnpct);
    c->has_hardwarn = fb_limit_get(&d->hardwarn, n, &c->hardwarn);
    if (!has_fail) c->fail = 0;
    if (!has_failpct) c->failpct = 0;
    if (!c->has_warnpct) c->warnpct = 0;
    /* with no threshold at all every pixel must be equal; with only statistics (FLIP's included), they decide */
    c->abs_test =
        has_fail || has_failpct || !(c->has_rmse || c->has_psnr || c->has_ssim || c->has_hardfail || d->flip_fail.set);
    if (!c->has_warn && (c->has_warnpct || c->has_hardwarn)) c->warn = 0, c->has_warn = c->has_warnpct;
}
