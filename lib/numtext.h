/*
 * lib/numtext.h — internal: numbers as the .amp text holds them, fast.
 * Writing `%.10g` and reading a plain decimal back were a fifth of
 * `slice --continuous` and most of `gcode`'s reading on large parts; both
 * take an exact arithmetic path when it gives printf's and strtod's very
 * bytes and values, and fall back to them otherwise (never a different
 * result, only a different speed).
 */
#ifndef AMPATH_LIB_NUMTEXT_H
#define AMPATH_LIB_NUMTEXT_H

#include <stddef.h>

/* Room for any number amp_g10_format writes, with its NUL. */
#define AMP_G10_MAX 32

/* v with 10 significant digits: the value strtod gives for printf("%.10g", v). */
double amp_g10_round(double v);

/* printf("%.10g", v) into @p out (at least AMP_G10_MAX bytes); returns the length. */
size_t amp_g10_format(double v, char *out);

/* The value of the @p len characters at @p s as strtod reads them, when they are a plain decimal
 * ([-+]digits[.digits], at most 19 significant digits and 22 decimals): 1 and *out set; 0 otherwise (the
 * caller then asks strtod, which also knows exponents, hexadecimal and the rest). */
int amp_dec_parse(const char *s, size_t len, double *out);

#endif
