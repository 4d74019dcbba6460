/* Numbers as the .amp text holds them (see numtext.h). */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "numtext.h"

static const double p10[23] = {1e0,  1e1,  1e2,  1e3,  1e4,  1e5,  1e6,  1e7,  1e8,  1e9,  1e10, 1e11,
                               1e12, 1e13, 1e14, 1e15, 1e16, 1e17, 1e18, 1e19, 1e20, 1e21, 1e22};

/*
 * The 10 significant digits of a = |v| as an integer m (1e9 <= m < 1e10) and the decimal exponent e of the
 * first one (a ~ m 10^(e-9)), by arithmetic: a 10^(9-e) is rounded once, by at most 2e-6 at m < 1e10, so
 * its rounding to m is printf's unless it lies within 1e-4 of a half step: then 0 (use printf).
 */
static int g10_digits(double a, double *m, int *e)
{
    double f;
    int k;
    if (!(a > 1e-12) || !(a < 1e12))
        return 0;
    /* the exponent by comparisons (log10 and floor were half of formatting a vertex); one off either way
     * near a decade is corrected below, as floor(log10(a)) was */
    if (a >= 1.0)
        for (k = 0; k < 12 && a >= p10[k + 1]; k++)
            ;
    else
        for (k = -1; k > -12 && a * p10[-k] < 1.0; k--)
            ;
    *e = k;
    if (*e >= 9)
        return 0;
    *m = a * p10[9 - *e];
    if (*m >= 1e10) {
        if (++*e > 9)
            return 0;
        *m = a * p10[9 - *e];
    } else if (*m < 1e9) {
        if (9 - --*e > 22)
            return 0;
        *m = a * p10[9 - *e];
    }
    if (*m < 1e9 || *m >= 1e10)
        return 0;
    f = *m - (double)(uint64_t)*m; /* 1e9 <= m < 1e10: the cast is floor */
    if (fabs(f - 0.5) < 1e-4)
        return 0;
    *m = (double)(uint64_t)(*m + 0.5);
    if (*m >= 1e10) { /* 9999999999.6 rounds up to the next decade */
        *m = 1e9;
        ++*e;
    }
    return *e <= 9;
}

static double g10_round_slow(double v)
{
    char buf[AMP_G10_MAX];
    snprintf(buf, sizeof buf, "%.10g", v);
    return strtod(buf, NULL);
}

/* m / p (or m p) is rounded once, as strtod rounds the decimal m 10^-k (m < 2^53, p = 10^k exact, k <= 22) */
double amp_g10_round(double v)
{
    double m;
    int e;
    if (v == 0)
        return v;
    if (!g10_digits(fabs(v), &m, &e))
        return g10_round_slow(v);
    return copysign(m / p10[9 - e], v);
}

size_t amp_g10_format(double v, char *out)
{
    char d[11];
    double m;
    int e, k, nd;
    size_t n = 0;
    uint64_t u;
    if (v == 0 || !g10_digits(fabs(v), &m, &e) || e < -4)
        return (size_t)snprintf(out, AMP_G10_MAX, "%.10g", v); /* -0, exponent notation, near halves */
    for (u = (uint64_t)m, k = 9; k >= 0; k--, u /= 10)
        d[k] = (char)('0' + u % 10);
    for (nd = 10; nd > 1 && d[nd - 1] == '0'; nd--)
        ; /* %g drops trailing zeros */
    if (v < 0)
        out[n++] = '-';
    if (e < 0) {
        out[n++] = '0';
        out[n++] = '.';
        for (k = -1; k > e; k--)
            out[n++] = '0';
        for (k = 0; k < nd; k++)
            out[n++] = d[k];
    } else {
        for (k = 0; k <= e; k++)
            out[n++] = d[k];
        if (nd > e + 1)
            out[n++] = '.';
        for (k = e + 1; k < nd; k++)
            out[n++] = d[k];
    }
    out[n] = '\0';
    return n;
}

/* Clinger's fast path: m < 2^53 and 10^k both exact, so m / 10^k is rounded once, as strtod rounds. */
int amp_dec_parse(const char *s, size_t len, double *out)
{
    size_t i = 0;
    uint64_t m = 0;
    int neg = 0, digits = 0, frac = 0, point = 0, sig = 0;
    if (i < len && (s[i] == '-' || s[i] == '+'))
        neg = s[i++] == '-';
    for (; i < len; i++) {
        char c = s[i];
        if (c == '.' && !point) {
            point = 1;
            continue;
        }
        if (c < '0' || c > '9')
            return 0;
        digits++;
        frac += point;
        if (m == 0 && c == '0')
            continue; /* leading zeros are not significant */
        if (++sig > 19)
            return 0;
        m = m * 10 + (uint64_t)(c - '0');
    }
    if (digits == 0 || frac > 22 || m > ((uint64_t)1 << 53))
        return 0;
    *out = (double)m / p10[frac];
    if (neg)
        *out = -*out;
    return 1;
}
