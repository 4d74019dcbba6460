/* Numbers as the .amp text holds them (lib/numtext.c): the fast paths give printf's bytes and strtod's values. */
#include <check.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "../lib/numtext.h"

/* A reproducible spread of doubles: every decade from 1e-14 to 1e14, both signs, and the hard cases. */
static uint64_t rng = 0x9E3779B97F4A7C15ULL;
static double next_value(void)
{
    double mant, v;
    int dec;
    rng ^= rng << 13;
    rng ^= rng >> 7;
    rng ^= rng << 17;
    mant = (double)(rng >> 11) / 9007199254740992.0; /* [0, 1) */
    dec = (int)(rng % 29) - 14;
    v = (1.0 + 9.0 * mant) * pow(10.0, dec);
    return rng & 0x100000 ? -v : v;
}

static const double edges[] = {0.0,         -0.0,        1.0,          -1.0,         0.1,         0.2,
                               0.225,       1e-4,        9.99999999995e-5, 1e-5,      123456789.0, 1234567890.0,
                               9999999999.4, 9999999999.6, 99999.999995, 0.30000000000000004, 18.37358849, 2.5e-12,
                               1e12,        1e-300,      1e300,        5e-324};

START_TEST(g10_format_writes_printfs_bytes)
{
    char a[AMP_G10_MAX], b[AMP_G10_MAX];
    size_t i, n;
    for (i = 0; i < sizeof edges / sizeof edges[0] + 200000; i++) {
        double v = i < sizeof edges / sizeof edges[0] ? edges[i] : next_value();
        if (i % 3 == 1) /* a value printed with fewer digits than it holds: a tie at the 10th digit */
            v = strtod((snprintf(b, sizeof b, "%.11g", v), b), NULL) + 0.0;
        n = amp_g10_format(v, a);
        snprintf(b, sizeof b, "%.10g", v);
        ck_assert_msg(strcmp(a, b) == 0, "%.17g: '%s' vs printf '%s'", v, a, b);
        ck_assert_uint_eq(n, strlen(b));
    }
    /* at every decade and a few ulps either side of it: the writer finds the exponent by comparisons */
    for (i = 0; i <= 26 * 7; i++) {
        double d = pow(10.0, (double)(i / 7) - 13.0), v = d;
        int k;
        for (k = 0; k < (int)(i % 7) - 3; k++)
            v = nextafter(v, HUGE_VAL);
        for (k = 0; k < 3 - (int)(i % 7); k++)
            v = nextafter(v, 0.0);
        amp_g10_format(v, a);
        snprintf(b, sizeof b, "%.10g", v);
        ck_assert_msg(strcmp(a, b) == 0, "%.17g: '%s' vs printf '%s'", v, a, b);
    }
}
END_TEST

START_TEST(g10_round_is_the_value_read_back)
{
    char b[AMP_G10_MAX];
    size_t i;
    for (i = 0; i < 200000; i++) {
        double v = i < sizeof edges / sizeof edges[0] ? edges[i] : next_value(), r = amp_g10_round(v);
        snprintf(b, sizeof b, "%.10g", v);
        ck_assert_msg(memcmp(&r, &(double){strtod(b, NULL)}, sizeof r) == 0, "%.17g rounds to %.17g, not %s", v, r, b);
    }
}
END_TEST

START_TEST(dec_parse_reads_strtods_value_or_declines)
{
    static const char *declined[] = {"1e5", "0x10", "inf", "nan", "", "-", ".", "1.2.3", "12a", "1 2",
                                     "12345678901234567890", "0.00000000000000000000001"};
    char b[64];
    size_t i;
    double v;
    for (i = 0; i < 300000; i++) {
        double x = next_value(), y;
        int prec = (int)(i % 12);
        if (i % 2)
            snprintf(b, sizeof b, "%.*f", prec, x);
        else
            snprintf(b, sizeof b, "%.10g", x);
        if (amp_dec_parse(b, strlen(b), &v)) {
            y = strtod(b, NULL);
            ck_assert_msg(memcmp(&v, &y, sizeof v) == 0, "'%s': %.17g vs strtod %.17g", b, v, y);
        } else /* what the .amp writer writes (10 digits, no exponent) always takes the fast path */
            ck_assert_msg(i % 2 == 1 || strchr(b, 'e'), "'%s' declined", b);
    }
    ck_assert_int_eq(amp_dec_parse("-0", 2, &v), 1);
    ck_assert(v == 0 && signbit(v));
    ck_assert_int_eq(amp_dec_parse("+5.", 3, &v), 1);
    ck_assert(v == 5.0);
    ck_assert_int_eq(amp_dec_parse("12.5xyz", 4, &v), 1); /* only the given length counts */
    ck_assert(v == 12.5);
    for (i = 0; i < sizeof declined / sizeof declined[0]; i++)
        ck_assert_msg(amp_dec_parse(declined[i], strlen(declined[i]), &v) == 0, "'%s' accepted", declined[i]);
}
END_TEST

int main(void)
{
    Suite *s = suite_create("numtext");
    TCase *tc = tcase_create("numtext");
    SRunner *sr;
    int nf;
    tcase_add_test(tc, g10_format_writes_printfs_bytes);
    tcase_add_test(tc, g10_round_is_the_value_read_back);
    tcase_add_test(tc, dec_parse_reads_strtods_value_or_declines);
    suite_add_tcase(s, tc);
    sr = srunner_create(s);
    srunner_run_all(sr, CK_NORMAL);
    nf = srunner_ntests_failed(sr);
    srunner_free(sr);
    return nf == 0 ? EXIT_SUCCESS : EXIT_FAILURE;
}
