/*
 * wsgctl script: the Lua scripts on the gripper, through the emulator's
 * control channel (--control only: a real gripper has no such channel,
 * its scripts are run from its web page). "script run FILE", "script
 * stop", "script status" and "script output" each send the channel's
 * line of the same name and print what it answers for people (status as
 * named values, output as the text the script printed) or, with -q, for
 * scripts. The channel's JSON is read here with just what its answers
 * need: the daemon writes them, keys are unique and strings escape only
 * what JSON requires.
 */
#define _GNU_SOURCE /* getcwd, open_memstream under -std=c99 */

#include "wsgctl.h"

#include <ctype.h>
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

/* The channel's answers are at most 2 KiB; room for a longer one. */
#define SCRIPT_LINE_MAX 4096
/* A script's path as it goes into "script run": realpath's bound. */
#define SCRIPT_PATH_MAX 4096

/* ---- reading the channel's JSON ---- */

/* Where the value of "key" starts, or NULL. */
static const char *json_at(const char *json, const char *key)
{
    char pat[40];
    const char *p;

    snprintf(pat, sizeof pat, "\"%s\":", key);
    p = strstr(json, pat);
    return p ? p + strlen(pat) : NULL;
}

static int hex_digit(int ch)
{
    if (ch >= '0' && ch <= '9')
        return ch - '0';
    ch = tolower(ch);
    return ch >= 'a' && ch <= 'f' ? ch - 'a' + 10 : -1;
}

/* The string value of key, unescaped, into out (cut to cap, no
 * terminator added: it may hold NULs), its length into *n. 1, 0 for
 * null, -1 when it is neither. \uXXXX becomes UTF-8; the daemon writes
 * it only for control bytes, which stay one byte. */
static int json_str(const char *json, const char *key, char *out, size_t cap,
                    size_t *n)
{
    const char *p = json_at(json, key);

    *n = 0;
    if (!p)
        return -1;
    if (!strncmp(p, "null", 4))
        return 0;
    if (*p++ != '"')
        return -1;
    while (*p && *p != '"') {
        unsigned long u;
        char ch = *p++;

        if (ch == '\\') {
            if (!*p)
                return -1; /* a line cut inside an escape */
            ch = *p++;
            switch (ch) {
            case 'n':
                ch = '\n';
                break;
            case 't':
                ch = '\t';
                break;
            case 'r':
                ch = '\r';
                break;
            case 'b':
                ch = '\b';
                break;
            case 'f':
                ch = '\f';
                break;
            case '"':
            case '\\':
            case '/':
                break;
            case 'u':
                u = 0;
                for (int i = 0; i < 4; i++) {
                    int d = hex_digit((unsigned char)*p);

                    if (d < 0)
                        return -1;
                    u = u << 4 | (unsigned long)d;
                    p++;
                }
                if (u < 0x80) {
                    ch = (char)u;
                    break;
                }
                if (u < 0x800) {
                    if (*n + 2 <= cap) {
                        out[(*n)++] = (char)(0xC0 | u >> 6);
                        out[(*n)++] = (char)(0x80 | (u & 0x3F));
                    }
                } else if (*n + 3 <= cap) {
                    out[(*n)++] = (char)(0xE0 | u >> 12);
                    out[(*n)++] = (char)(0x80 | (u >> 6 & 0x3F));
                    out[(*n)++] = (char)(0x80 | (u & 0x3F));
                }
                continue;
            default:
                return -1;
            }
        }
        if (*n < cap)
            out[(*n)++] = ch;
    }
    return *p == '"' ? 1 : -1;
}

static int json_true(const char *json, const char *key)
{
    const char *p = json_at(json, key);

    return p && !strncmp(p, "true", 4);
}

/* ---- the subcommands ---- */

int wsgctl_path(const char *what, const char *file, char *path, size_t cap)
{
    for (const char *p = file; *p; p++)
        if (isspace((unsigned char)*p)) {
            /* The channel splits its lines at blanks. */
            err("%s: a path with a blank cannot go through the "
                "control channel: \"%s\"",
                what, file);
            return EXIT_USAGE;
        }
    if (file[0] == '/') {
        if ((size_t)snprintf(path, cap, "%s", file) >= cap) {
            err("%s: path too long: \"%s\"", what, file);
            return EXIT_USAGE;
        }
    } else {
        char cwd[SCRIPT_PATH_MAX];

        if (!getcwd(cwd, sizeof cwd)) {
            err("%s: the working directory: %s", what, strerror(errno));
            return EXIT_USAGE;
        }
        if ((size_t)snprintf(path, cap, "%s/%s", cwd, file) >= cap) {
            err("%s: path too long: \"%s\"", what, file);
            return EXIT_USAGE;
        }
    }
    return 0;
}

static int script_run(struct ctx *x, const char *file)
{
    char path[SCRIPT_PATH_MAX], cmd[SCRIPT_PATH_MAX + 16];
    char line[SCRIPT_LINE_MAX];
    const char *rest;
    int rc = wsgctl_path("script run", file, path, sizeof path);

    if (rc)
        return rc;
    snprintf(cmd, sizeof cmd, "script run %s", path);
    return control_line(x, cmd, line, sizeof line, &rest);
}

static int script_stop(struct ctx *x)
{
    char line[SCRIPT_LINE_MAX];
    const char *rest;

    /* Not running is no error: afterwards none runs, as asked. */
    return control_line(x, "script stop", line, sizeof line, &rest);
}

static int script_status(struct ctx *x)
{
    char line[SCRIPT_LINE_MAX], text[SCRIPT_LINE_MAX];
    const char *json, *p;
    double memory, memory_max, preempted;
    size_t n;
    int rc = control_line(x, "script status", line, sizeof line, &json);

    if (rc)
        return rc;
    if (x->o.jo) {
        /* The channel's object as it is: it is JSON already. */
        jout_add(x->o.jo, ",\"answer\":%s", json);
        return EXIT_OK;
    }
    if (x->o.quiet) {
        puts(json);
        return EXIT_OK;
    }
    if (json_str(json, "state", text, sizeof text - 1, &n) != 1 ||
        wsg_json_num(json, "memory", &memory) ||
        wsg_json_num(json, "memory_max", &memory_max) ||
        wsg_json_num(json, "preempted", &preempted) ||
        !(p = json_at(json, "registered")) || *p != '[') {
        err("control channel: unexpected script status: %s", json);
        return EXIT_CONN;
    }
    text[n] = '\0';
    if (json_true(json, "running"))
        printf("script running (%s)\n", text);
    else
        printf("script %s\n",
               json_true(json, "failed") ? "failed" : "not running");
    if (json_str(json, "file", text, sizeof text - 1, &n) == 1)
        printf("file %.*s\n", (int)n, text);
    if (json_str(json, "error", text, sizeof text - 1, &n) == 1)
        printf("error %.*s\n", (int)n, text);
    /* "[176,177]" as the IDs are written everywhere else: "B0h B1h". */
    fputs("registered", stdout);
    if (p[1] == ']')
        fputs(" none", stdout);
    for (p++; *p && *p != ']';) {
        char *end;
        unsigned long id = strtoul(p, &end, 10);

        if (end == p)
            break;
        printf(" %02lXh", id);
        p = *end == ',' ? end + 1 : end;
    }
    putchar('\n');
    printf("memory %.0f of %.0f bytes\n", memory, memory_max);
    printf("preempted %.0f\n", preempted);
    return EXIT_OK;
}

/* Everything the emulator still holds, as printed, in as many answers as
 * it takes; up to the end of the first answer, so a script that prints on
 * does not keep wsgctl reading. */
static int script_output(struct ctx *x)
{
    char line[SCRIPT_LINE_MAX], text[SCRIPT_LINE_MAX], cmd[48];
    double from = 0, next, end, stop = -1, lost, lost_total = 0;
    const char *json;
    char *all = NULL;
    size_t n, all_len = 0;
    FILE *out = stdout;
    int rc;

    /* --json: the whole text as one string, gathered first. */
    if (x->o.jo && !(out = open_memstream(&all, &all_len))) {
        err("script output: %s", strerror(errno));
        return EXIT_CONN;
    }
    for (;;) {
        snprintf(cmd, sizeof cmd, "script output %.0f", from);
        rc = control_line(x, cmd, line, sizeof line, &json);
        if (rc)
            goto out;
        if (json_str(json, "text", text, sizeof text, &n) != 1 ||
            wsg_json_num(json, "lost", &lost) ||
            wsg_json_num(json, "next", &next) ||
            wsg_json_num(json, "end", &end)) {
            err("control channel: unexpected script output: %s", json);
            rc = EXIT_CONN;
            goto out;
        }
        fwrite(text, 1, n, out);
        lost_total += lost;
        if (stop < 0)
            stop = end;
        if (next >= stop || next <= from)
            break;
        from = next;
    }
    if (lost_total > 0 && !x->o.quiet && !x->o.jo)
        err("script output: the first %.0f bytes are no longer kept (the "
            "emulator keeps the last 64 KiB)",
            lost_total);
    rc = EXIT_OK;
out:
    if (out != stdout) {
        fclose(out);
        if (rc == EXIT_OK) {
            jout_str(x->o.jo, "text", all, all_len);
            jout_add(x->o.jo, ",\"lost\":%.0f", lost_total);
        }
        free(all);
    }
    return rc;
}

int c_script(struct ctx *x, int argc, char **argv)
{
    const char *sub = argv[0];

    if (!strcmp(sub, "run") && argc == 2)
        return script_run(x, argv[1]);
    if (argc == 1 && !strcmp(sub, "stop"))
        return script_stop(x);
    if (argc == 1 && !strcmp(sub, "status"))
        return script_status(x);
    if (argc == 1 && !strcmp(sub, "output"))
        return script_output(x);
    err("usage: wsgctl --control HOST:PORT script run FILE|stop|status|"
        "output");
    return EXIT_USAGE;
}
