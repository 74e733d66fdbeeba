/*
 * wsgbench's rows and its one table: percentiles of the samples, a row per
 * figure with the emulator's value, the reference's and a target, and the
 * table printed at the end with their ratio and "ok" or "MISSED" (a
 * missed target is a figure, not an error).
 */
#define _GNU_SOURCE /* sched_setaffinity, pipe2, prctl, strndup */

#include "wsgbench.h"

#include <arpa/inet.h>
#include <dirent.h>
#include <errno.h>
#include <fcntl.h>
#include <getopt.h>
#include <math.h>
#include <netinet/in.h>
#include <poll.h>
#include <sched.h>
#include <signal.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/epoll.h>
#include <sys/prctl.h>
#include <sys/resource.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

static int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;

    return (x > y) - (x < y);
}

/* Nearest-rank percentiles; sorts v. */
struct dist dist_of(double *v, size_t n)
{
    struct dist d = {NAN, NAN, NAN};

    if (n == 0)
        return d;
    qsort(v, n, sizeof *v, cmp_double);
    d.p50 = v[(size_t)ceil(0.50 * (double)n) - 1];
    d.p99 = v[(size_t)ceil(0.99 * (double)n) - 1];
    d.max = v[n - 1];
    return d;
}

int alternate(struct bench *b, int (*take)(void *ctx, int side, double *us),
              int (*turn)(void *ctx, int side, int on), void *ctx,
              struct dist dd[2])
{
    size_t per = (size_t)(b->o.samples / ROUNDS), warm, i;
    double *lat[2] = {NULL, NULL}, dummy;
    size_t n[2] = {0, 0};
    int round, k, side, rc = -1;

    dd[0].p50 = dd[0].p99 = dd[0].max = NAN;
    dd[1] = dd[0];
    if (per == 0)
        per = 1;
    warm = per < 200 ? 200 : per > 2000 ? 2000 : per;
    for (side = 0; side < 2; side++) {
        lat[side] = malloc(per * ROUNDS * sizeof(double));
        if (!lat[side])
            goto out;
    }
    for (i = 0; i < warm; i++)
        if (take(ctx, 0, &dummy) < 0 || take(ctx, 1, &dummy) < 0)
            goto out;
    for (round = 0; round < ROUNDS; round++) {
        for (k = 0; k < 2; k++) {
            side = (round + k) % 2;
            if (turn && turn(ctx, side, 1) < 0)
                goto out;
            for (i = 0; i < per; i++)
                if (take(ctx, side, &lat[side][n[side]++]) < 0)
                    break;
            if (turn)
                turn(ctx, side, 0);
            if (i < per)
                goto out;
        }
    }
    dd[0] = dist_of(lat[0], n[0]);
    dd[1] = dist_of(lat[1], n[1]);
    rc = 0;
out:
    free(lat[0]);
    free(lat[1]);
    return rc;
}

struct row *add_row(struct bench *b, const char *label, double emu, double ref,
                    int decimals)
{
    struct row *r = &b->rows[b->nrows < ROWS_MAX ? b->nrows++ : ROWS_MAX - 1];

    memset(r, 0, sizeof *r);
    snprintf(r->label, sizeof r->label, "%s", label);
    r->emu = emu;
    r->ref = ref;
    r->decimals = decimals;
    return r;
}

void set_target(struct row *r, enum target tk, double tv, int on_ratio,
                const char *text)
{
    r->tk = tk;
    r->tv = tv;
    r->on_ratio = on_ratio;
    snprintf(r->ttext, sizeof r->ttext, "%s", text);
}
static void fmt_value(char *buf, size_t cap, double v, int decimals)
{
    if (v == NOT_APPLIED)
        snprintf(buf, cap, "-");
    else if (isnan(v))
        snprintf(buf, cap, "n/a");
    else
        snprintf(buf, cap, "%.*f", decimals, v);
}

void print_table(const struct bench *b)
{
    if (b->attach && b->pid[EMU] > 0)
        printf("wsgbench %s: attached wsgemu (pid %d) vs wsgref", WSG_VERSION,
               (int)b->pid[EMU]);
    else if (b->attach)
        printf("wsgbench %s: attached wsgemu vs wsgref", WSG_VERSION);
    else
        printf("wsgbench: wsgemu %s vs wsgref", WSG_VERSION);
    printf(", %ld samples, %d CPU%s", b->o.samples, b->ncpu,
           b->ncpu == 1 ? "" : "s");
    if (b->cpu_bench >= 0 && b->attach)
        printf(" (reference%s on CPU %d, bench on CPU %d; the attached "
               "emulator is not pinned)",
               b->o.fleet > 0 ? " and fleet" : "", b->cpu_server,
               b->cpu_bench);
    else if (b->cpu_bench >= 0)
        printf(" (servers on CPU %d, bench on CPU %d)", b->cpu_server,
               b->cpu_bench);
    else if (b->attach)
        printf(" (nothing pinned)");
    printf("\n%-36s %10s %10s %7s  %s\n", "figure", "emulator", "reference",
           "ratio", "target");
    for (int i = 0; i < b->nrows; i++) {
        const struct row *r = &b->rows[i];
        char e[24], f[24], q[24];
        double ratio = NAN, v;
        const char *mark = "";

        fmt_value(e, sizeof e, r->emu, r->decimals);
        fmt_value(f, sizeof f, r->ref, r->decimals);
        if (r->ref == NOT_APPLIED) {
            snprintf(q, sizeof q, "-");
        } else {
            if (!isnan(r->emu) && !isnan(r->ref) && r->ref > 0)
                ratio = r->emu / r->ref;
            /* 0 against 0 (idle) has no ratio, but is no failure. */
            fmt_value(q, sizeof q, r->ref == 0 ? NOT_APPLIED : ratio, 2);
        }
        v = r->on_ratio ? ratio : r->emu;
        if (r->tk != T_NONE) {
            int ok = r->tk == T_LT   ? v < r->tv
                     : r->tk == T_LE ? v <= r->tv
                     : r->tk == T_GE ? v >= r->tv
                     : r->tk == T_EQ ? v == r->tv
                                     : fabs(v - r->tv) <= r->tol;
            mark = isnan(v) ? "n/a" : ok ? "ok" : "MISSED";
        }
        if (*mark)
            printf("%-36s %10s %10s %7s  %-13s %s\n", r->label, e, f, q,
                   r->ttext, mark);
        else
            printf("%-36s %10s %10s %7s\n", r->label, e, f, q);
    }
    fflush(stdout);
}
