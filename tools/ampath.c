/* ampath — command-line front end of libampath (docs/interfaces.md §4). */
#include <errno.h>
#include <stdio.h>
#include <string.h>

#include "cli.h"

typedef struct command {
    const char *name;
    const char *usage;
    int (*run)(int argc, char **argv);
} command;

static const command commands[] = {
#define AMP_CMD(name) {#name, cmd_##name##_usage, cmd_##name},
#include "commands.inc"
#undef AMP_CMD
};

static const size_t ncommands = sizeof commands / sizeof commands[0];

static const command *find(const char *name)
{
    size_t i;
    for (i = 0; i < ncommands; i++)
        if (strcmp(commands[i].name, name) == 0)
            return &commands[i];
    return NULL;
}

static void print_summary(FILE *f, const char *usage)
{
    const char *nl = strchr(usage, '\n');
    fprintf(f, "%.*s\n", nl ? (int)(nl - usage) : (int)strlen(usage), usage);
}

static int overview(FILE *f)
{
    size_t i;
    fprintf(f, "usage: ampath <command> [options]   (ampath help <command> for details)\n\ncommands:\n");
    for (i = 0; i < ncommands; i++) {
        fprintf(f, "  %-10s ", commands[i].name);
        print_summary(f, commands[i].usage);
    }
    fprintf(f, "\nEvery computing command accepts --json (one JSON object on stdout) and -o FILE.\n"
               "Exit status: 0 success, 1 failed check, 2 bad usage or input.\n");
    return f == stdout ? CLI_OK : CLI_USAGE;
}

/* A product or figures lost on a full disk or a closed pipe are a failure, not a success (exit 2, the system's
 * reason); a failed check (1) or refusal (2) keeps its own code. */
static int finish(const char *cmd, int rc)
{
    int bad = fflush(stdout) != 0 || ferror(stdout);
    if (bad && rc == CLI_OK)
        return cli_fail(cmd, CLI_USAGE, "writing standard output: %s", strerror(errno ? errno : EIO));
    return rc;
}

static int run(int argc, char **argv)
{
    const command *c;
    if (argc < 2)
        return overview(stderr);
    if (strcmp(argv[1], "--version") == 0 || strcmp(argv[1], "version") == 0) {
        if (argc > 2)
            return cli_fail("ampath", CLI_USAGE, "%s takes no argument, got '%s'", argv[1], argv[2]);
        printf("ampath %s\n", AMP_VERSION_STRING);
        return CLI_OK;
    }
    if (strcmp(argv[1], "help") == 0 || strcmp(argv[1], "--help") == 0 || strcmp(argv[1], "-h") == 0) {
        if (argc < 3 || strcmp(argv[2], "help") == 0)
            return overview(stdout);
        c = find(argv[2]);
        if (!c)
            return cli_fail("help", CLI_USAGE, "unknown command '%s'", argv[2]);
        fputs(c->usage, stdout);
        return CLI_OK;
    }
    c = find(argv[1]);
    if (!c)
        return cli_fail("ampath", CLI_USAGE, "unknown %s '%s' (ampath help lists the commands)",
                        argv[1][0] == '-' ? "option" : "command", argv[1]);
    if (argc >= 3 && (strcmp(argv[2], "--help") == 0 || strcmp(argv[2], "-h") == 0)) {
        fputs(c->usage, stdout);
        return CLI_OK;
    }
    return c->run(argc - 1, argv + 1);
}

int main(int argc, char **argv)
{
    errno = 0;
    return finish(argc > 1 && argv[1][0] != '-' ? argv[1] : "ampath", run(argc, argv));
}
