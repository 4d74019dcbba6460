/* ampath-vprinter's options: numbers are validated as ampath's are (tools/cli.c cli_number, cli_integer). */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/wait.h>

#include "testutil.h"

/* Exit status of the virtual printer run with @p args (stdout and stderr discarded). */
static int vprinter_status(const char *args)
{
    char cmd[1024];
    int st;
    /* an accepted option starts the printer, which runs until killed: timeout ends it (status 124) */
    snprintf(cmd, sizeof cmd, "timeout 10 '%s' %s > /dev/null 2>&1", fx_prog("AMP_VPRINTER"), args);
    st = system(cmd);
    return WIFEXITED(st) ? WEXITSTATUS(st) : -1;
}

START_TEST(malformed_numbers_are_refused_with_exit_2)
{
    static const char *const bad[] = {"--bufsize 4x", "--bufsize ''", "--planner 1.5", "--turnaround fast",
                                      "--baud 1e999", "--seed 12z", "--busy-at 3,4", "--corrupt-in nan",
                                      "--reset-after 12x", "--lose-ok 3.5", "--hangup-after two"};
    size_t i;
    for (i = 0; i < sizeof bad / sizeof bad[0]; i++)
        ck_assert_msg(vprinter_status(bad[i]) == 2, "ampath-vprinter %s was accepted", bad[i]);
}
END_TEST

START_TEST(help_and_well_formed_numbers_still_parse)
{
    /* --help exits 0 after parsing the options before it: the numbers given are accepted */
    ck_assert_int_eq(vprinter_status("--bufsize 8 --turnaround 0.5 --baud 115200 --seed 7 --help"), 0);
}
END_TEST

static Suite *vprinter_suite(void)
{
    Suite *s = suite_create("vprinter");
    TCase *tc = tcase_create("options");
    tcase_add_test(tc, malformed_numbers_are_refused_with_exit_2);
    tcase_add_test(tc, help_and_well_formed_numbers_still_parse);
    suite_add_tcase(s, tc);
    return s;
}

FX_TEST_MAIN(vprinter_suite)
