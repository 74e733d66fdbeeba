/*
 * The control channel: a listening TCP socket and up to WSG_CTL_CLIENTS_MAX
 * clients, each with a line buffer. The clients are a set of stream peers
 * (peer.h), as the gripper's TCP connections are: each has a bounded output
 * queue, so a client that stops reading is dropped instead of blocking the
 * loop.
 *
 * Commands act at once, between the loop's model steps: the world setters
 * change what the model sees and the model is settled before the answer
 * goes out (a removed part is lost then, with the statistics the manual
 * gives), and the time commands go to the loop, which alone deals with
 * time. "time step" runs its steps
 * synchronously before answering, so a test in lockstep knows that every
 * packet the steps caused was sent before the "ok".
 *
 * Like the TCP port's, a client that ends is only marked during the event
 * batch and freed by the reap after it (a hook on the reactor).
 */
#define _GNU_SOURCE

#include "control.h"

#include <arpa/inet.h>
#include <errno.h>
#include <limits.h>
#include <math.h>
#include <netinet/in.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/epoll.h>
#include <sys/socket.h>
#include <unistd.h>

#include "capture.h"
#include "gripper.h"
#include "peer.h"
#include "state.h"
#include "wsg/gcl.h"
#include "wsg/plant.h"

#define WSG_CTL_READ_CHUNK 1024u
#define WSG_CTL_REPLY_MAX  2048u
#define WSG_CTL_ARGS_MAX   4
/* "object box W D H MASS FRICTION" alone takes more. */
#define WSG_CTL_OBJECT_ARGS_MAX 7
/* "time step" at most one hour at once: the loop is blocked meanwhile. */
#define WSG_CTL_STEP_MS_MAX 3600000.0
/* With physics every step is run and costs: 2 us for one gripper in the
 * model's scene, up to some 10 us with the largest object pressed into
 * the pads. At most a minute of it at once, over all the grippers that
 * have it, so that the loop stays blocked for under a second. */
#define WSG_CTL_STEP_MS_PHYSICS 60000.0

struct wsg_ctl;

/* A client on the socket: its session, and the peer it answers through. */
struct wsg_ctl_client {
    struct wsg_ctl *ctl;
    struct wsg_ctl_session s;
    struct wsg_peer peer; /* last: the set allocates the struct around it */
};

/* What a command runs with: the channel and the session it came from. */
struct ctl_ctx {
    struct wsg_ctl *ctl;
    struct wsg_ctl_session *s;
};

struct wsg_ctl {
    struct wsg_watch watch; /* the listening socket; fd -1: none */
    struct wsg_reactor *reactor;
    struct wsg_sched *sched;
    struct wsg_gripper *cur; /* the line being run acts on this one */
    /* The daemon's capture, which `capture` starts and stops; NULL: the
     * command is refused (the web page's channel has none: a page must
     * not write files). */
    struct wsg_capture *capture;
    char local[WSG_ADDR_LEN];
    struct wsg_peer_set clients;
};

static struct wsg_ctl_client *client_of(struct wsg_peer *p)
{
    return WSG_PEER_OWNER(p, struct wsg_ctl_client, peer);
}

/* One answer line; the newline is added here. */
static void reply(struct ctl_ctx *c, const char *fmt, ...)
{
    char buf[WSG_CTL_REPLY_MAX];
    va_list ap;
    size_t n;

    if (c->s->closed)
        return;
    va_start(ap, fmt);
    n = wsg_gcl_line_vformat(buf, sizeof buf, fmt, ap);
    va_end(ap);
    if (n)
        c->s->answer(c->s->ctx, buf, n);
}

/* A command that changed the world answers "ok WHAT" and puts WHAT in the
 * communication log ("control event part 40 200"), before the settle
 * that follows shows its consequences there (a FAST STOP by a fault). */
static void changed(struct ctl_ctx *c, const char *fmt, ...)
    __attribute__((format(printf, 2, 3)));

static void changed(struct ctl_ctx *c, const char *fmt, ...)
{
    char what[WSG_CTL_REPLY_MAX - 4];
    va_list ap;

    va_start(ap, fmt);
    vsnprintf(what, sizeof what, fmt, ap);
    va_end(ap);
    wsg_log_event(&c->ctl->cur->tap, "control", what);
    reply(c, "ok %s", what);
}

/* ---- arguments ---- */

/* A whole finite number, nothing after it. */
static int parse_num(const char *s, double *v)
{
    char *end;

    errno = 0;
    *v = strtod(s, &end);
    return end != s && *end == '\0' && errno == 0 && isfinite(*v);
}

/* ---- commands ---- */

static void cmd_part(struct ctl_ctx *c, int argc, char **argv)
{
    struct wsg_axis *ax = wsg_device_axis(&c->ctl->cur->dev);
    struct wsg_plant *pl = wsg_axis_plant(ax);
    struct wsg_axis_range r =
        wsg_axis_config_range(wsg_axis_cfg(ax), WSG_AXIS_WIDTH);
    double width, stiffness = 0.0;

    if (strcmp(pl->ops->name, "builtin") != 0) {
        reply(c, "error part: the %s plant's world is objects (object)",
              pl->ops->name);
        return;
    }
    if (argc == 2 && strcmp(argv[1], "none") == 0) {
        wsg_axis_set_part(ax, -1.0, 0.0);
        changed(c, "part none");
        return;
    }
    if (argc < 2 || argc > 3) {
        reply(c, "error usage: part WIDTH [STIFFNESS] | part none");
        return;
    }
    if (!parse_num(argv[1], &width) || width < r.min || width > r.max) {
        reply(c, "error part: WIDTH must be a number of mm in %g..%g", r.min,
              r.max);
        return;
    }
    if (argc == 3 && (!parse_num(argv[2], &stiffness) || stiffness <= 0.0)) {
        reply(c, "error part: STIFFNESS must be a positive number of N/mm");
        return;
    }
    wsg_axis_set_part(ax, width, stiffness);
    /* The stiffness as taken: the model's default for none given. */
    wsg_axis_part(ax, &width, &stiffness);
    changed(c, "part %g %g", width, stiffness);
}

/* object box W D H | cylinder D L | sphere D [MASS [FRICTION]] | none:
 * a shape between the fingers, for a plant with physics (--physics
 * mujoco). Sizes in mm, mass in kg (default 0.1), friction (default 1). */
static void cmd_object(struct ctl_ctx *c, int argc, char **argv)
{
    static const char usage[] =
        "error usage: object box W D H | cylinder D L | sphere D "
        "[MASS [FRICTION]] | none";
    struct wsg_plant *p = wsg_axis_plant(wsg_device_axis(&c->ctl->cur->dev));
    struct wsg_object o;
    int n, i, r;

    memset(&o, 0, sizeof o);
    o.mass = 0.1;
    o.friction = 1.0;
    if (argc < 2) {
        reply(c, "%s", usage);
        return;
    }
    if (strcmp(argv[1], "none") == 0 && argc == 2)
        n = 0, o.kind = WSG_OBJECT_NONE;
    else if (strcmp(argv[1], "box") == 0)
        n = 3, o.kind = WSG_OBJECT_BOX;
    else if (strcmp(argv[1], "cylinder") == 0)
        n = 2, o.kind = WSG_OBJECT_CYLINDER;
    else if (strcmp(argv[1], "sphere") == 0)
        n = 1, o.kind = WSG_OBJECT_SPHERE;
    else {
        reply(c, "%s", usage);
        return;
    }
    if (argc < 2 + n || argc > 4 + n) {
        reply(c, "%s", usage);
        return;
    }
    for (i = 0; i < n; i++)
        if (!parse_num(argv[2 + i], &o.size[i]) || o.size[i] <= 0.0 ||
            o.size[i] > WSG_OBJECT_SIZE_MAX) {
            reply(c, "error object: sizes must be numbers of mm in 0..%g",
                  WSG_OBJECT_SIZE_MAX);
            return;
        }
    if ((argc > 2 + n && (!parse_num(argv[2 + n], &o.mass) || o.mass <= 0.0 ||
                          o.mass > 100.0)) ||
        (argc > 3 + n && (!parse_num(argv[3 + n], &o.friction) ||
                          o.friction < 0.0 || o.friction > 10.0))) {
        reply(c, "error object: MASS must be in 0..100 kg, FRICTION in "
                 "0..10");
        return;
    }
    r = p->ops->place(p, &o);
    if (r == -ENOTSUP) {
        reply(c,
              "error object: the %s plant has no objects (--physics "
              "mujoco has; here: part)",
              p->ops->name);
        return;
    }
    if (r == -EINVAL) {
        /* MuJoCo's compiler refused the body: its inertia is below what
         * it takes (a tiny, light object). */
        reply(c, "error object: the physics refuses it (too small or too "
                 "light to simulate)");
        return;
    }
    if (r < 0) {
        reply(c, "error object: %s", strerror(-r));
        return;
    }
    if (o.kind == WSG_OBJECT_NONE)
        changed(c, "object none");
    else
        changed(c, "object %s %g %g %g %g %g", argv[1], o.size[0], o.size[1],
                o.size[2], o.mass, o.friction);
}

/* pull N: pull on the object out of the fingers (0 stops pulling). */
static void cmd_pull(struct ctl_ctx *c, int argc, char **argv)
{
    struct wsg_plant *p = wsg_axis_plant(wsg_device_axis(&c->ctl->cur->dev));
    double n;
    int r;

    if (argc != 2 || !parse_num(argv[1], &n) || n < 0.0 || n > 10000.0) {
        reply(c, "error usage: pull N (0..10000 newtons)");
        return;
    }
    r = p->ops->pull(p, n);
    if (r == -ENOTSUP) {
        reply(c,
              "error pull: the %s plant has no objects (--physics mujoco "
              "has)",
              p->ops->name);
        return;
    }
    if (r == -ENOENT) {
        reply(c, "error pull: no object placed");
        return;
    }
    if (r < 0) {
        reply(c, "error pull: %s", strerror(-r));
        return;
    }
    changed(c, "pull %g", n);
}

static void cmd_obstacle(struct ctl_ctx *c, int argc, char **argv)
{
    struct wsg_axis *ax = wsg_device_axis(&c->ctl->cur->dev);
    struct wsg_plant *pl = wsg_axis_plant(ax);
    struct wsg_axis_range r =
        wsg_axis_config_range(wsg_axis_cfg(ax), WSG_AXIS_WIDTH);
    double width;

    if (strcmp(pl->ops->name, "builtin") != 0) {
        reply(c, "error obstacle: the %s plant's world is objects (object)",
              pl->ops->name);
        return;
    }
    if (argc != 2) {
        reply(c, "error usage: obstacle WIDTH | obstacle none");
        return;
    }
    if (strcmp(argv[1], "none") == 0) {
        wsg_axis_set_obstacle(ax, -1.0);
        changed(c, "obstacle none");
        return;
    }
    if (!parse_num(argv[1], &width) || width < r.min || width > r.max) {
        reply(c, "error obstacle: WIDTH must be a number of mm in %g..%g",
              r.min, r.max);
        return;
    }
    wsg_axis_set_obstacle(ax, width);
    changed(c, "obstacle %g", width);
}

static const struct {
    const char *name;
    uint32_t flag;
} faults[] = {{"temp-warning", WSG_SF_TEMP_WARNING},
              {"temp-fault", WSG_SF_TEMP_FAULT},
              {"power", WSG_SF_POWER_FAULT},
              {"current", WSG_SF_CURR_FAULT},
              {"finger", WSG_SF_FINGER_FAULT}};

static void cmd_fault(struct ctl_ctx *c, int argc, char **argv)
{
    size_t i;
    int on;

    if (argc != 3) {
        reply(c, "error usage: fault temp-warning|temp-fault|power|current|"
                 "finger on|off");
        return;
    }
    if (strcmp(argv[2], "on") == 0)
        on = 1;
    else if (strcmp(argv[2], "off") == 0)
        on = 0;
    else {
        reply(c, "error fault: say on or off, not '%s'", argv[2]);
        return;
    }
    for (i = 0; i < sizeof faults / sizeof faults[0]; i++) {
        if (strcmp(argv[1], faults[i].name) == 0) {
            wsg_axis_set_fault(wsg_device_axis(&c->ctl->cur->dev),
                               faults[i].flag, on);
            changed(c, "fault %s %s", faults[i].name, on ? "on" : "off");
            return;
        }
    }
    reply(c,
          "error fault: unknown fault '%s' (temp-warning, temp-fault, "
          "power, current, finger)",
          argv[1]);
}

static void reply_time(struct ctl_ctx *c)
{
    char t[32];

    /* Steps run by hand may have left the gripper idle part way. */
    wsg_sched_touch(c->ctl->sched, c->ctl->cur);
    wsg_state_format_time(t, sizeof t,
                          wsg_axis_time(wsg_device_axis(&c->ctl->cur->dev)));
    reply(c, "ok %s", t);
}

static void cmd_time(struct ctl_ctx *c, int argc, char **argv)
{
    struct wsg_sched *l = c->ctl->sched;
    uint32_t step_us =
        wsg_axis_cfg(wsg_device_axis(&c->ctl->cur->dev))->step_us;
    double v;
    int r;

    if (argc == 1) {
        reply_time(c);
        return;
    }
    if (strcmp(argv[1], "pause") == 0 && argc == 2) {
        r = wsg_sched_pause(l);
        if (r < 0)
            reply(c, "error time pause: %s", strerror(-r));
        else
            reply(c, "ok paused");
        return;
    }
    if (strcmp(argv[1], "resume") == 0 && argc == 2) {
        r = wsg_sched_resume(l);
        if (r < 0)
            reply(c, "error time resume: %s", strerror(-r));
        else
            reply(c, "ok running at scale %g", l->scale);
        return;
    }
    if (strcmp(argv[1], "scale") == 0 && argc == 3) {
        if (!parse_num(argv[2], &v)) {
            reply(c, "error time scale: '%s' is not a number", argv[2]);
            return;
        }
        r = wsg_sched_set_scale(l, v);
        if (r == -EINVAL)
            reply(c, "error time scale: X must be in %g..%g",
                  WSG_SCHED_SCALE_MIN, WSG_SCHED_SCALE_MAX);
        else if (r < 0)
            reply(c, "error time scale: %s", strerror(-r));
        else
            reply(c, "ok scale %g%s", l->scale, l->paused ? " paused" : "");
        return;
    }
    if (strcmp(argv[1], "step") == 0 && argc == 3) {
        double us, max = WSG_CTL_STEP_MS_MAX;
        size_t i, physics = 0;

        for (i = 0; i < l->ngrippers; i++)
            physics += l->grippers[i].plant != NULL;
        if (physics)
            max = floor(WSG_CTL_STEP_MS_PHYSICS / (double)physics);
        if (!parse_num(argv[2], &v) || v <= 0.0 || v > max) {
            reply(c,
                  "error time step: MS must be a number of ms in "
                  "(0, %.0f]%s",
                  max, physics ? " with physics" : "");
            return;
        }
        /* Exactly the time asked for, or nothing: a lockstep test must
         * not drift by rounding. */
        us = v * 1000.0;
        if (fabs(us - floor(us + 0.5)) > 1e-6 ||
            (uint64_t)(us + 0.5) % step_us != 0) {
            reply(c,
                  "error time step: %s ms is not a whole number of %u us "
                  "steps",
                  argv[2], (unsigned)step_us);
            return;
        }
        r = wsg_sched_step(l, (uint64_t)(us + 0.5) / step_us);
        if (r == -EBUSY)
            reply(c, "error time step: not paused (time pause first)");
        else if (r < 0)
            reply(c, "error time step: %s", strerror(-r));
        else
            reply_time(c);
        return;
    }
    reply(c, "error usage: time | time scale X | time pause | time step MS | "
             "time resume");
}

/* Appends to buf at *used; a reply that does not fit is cut, never
 * overrun (it cannot happen with these keys). */
static void append(char *buf, size_t cap, size_t *used, const char *fmt, ...)
{
    va_list ap;
    int n;

    if (*used >= cap)
        return;
    va_start(ap, fmt);
    n = vsnprintf(buf + *used, cap - *used, fmt, ap);
    va_end(ap);
    if (n > 0)
        *used += (size_t)n;
}

/* The size of the patch the part presses on each finger's pad. */
static void cmd_patch(struct ctl_ctx *c, int argc, char **argv)
{
    struct wsg_axis *ax = wsg_device_axis(&c->ctl->cur->dev);
    double w, h;

    if (argc == 2 && strcmp(argv[1], "default") == 0) {
        wsg_axis_set_part_patch(ax, 0.0, 0.0);
        changed(c, "patch %g %g", WSG_AXIS_PATCH_MM, WSG_AXIS_PATCH_MM);
        return;
    }
    if (argc != 3 || !parse_num(argv[1], &w) || !parse_num(argv[2], &h) ||
        w <= 0.0 || h <= 0.0 || w > 1000.0 || h > 1000.0) {
        reply(c, "error usage: patch W H (mm, 0 < W, H <= 1000) | patch "
                 "default");
        return;
    }
    wsg_axis_set_part_patch(ax, w, h);
    changed(c, "patch %g %g", w, h);
}

/* finger: both as JSON; finger I KIND | device FILE | power on|off |
 * cells. */
static void cmd_finger(struct ctl_ctx *c, int argc, char **argv)
{
    struct wsg_gripper *g = c->ctl->cur;
    struct wsg_fingers *fs = &g->dev.fingers;
    char buf[WSG_CTL_REPLY_MAX - 8], err[512];
    size_t used = 0;
    int i, k;

    if (argc == 1) {
        uint32_t faults = wsg_axis_faults(wsg_device_axis(&g->dev));

        append(buf, sizeof buf, &used, "[");
        for (i = 0; i < WSG_FINGER_COUNT; i++)
            append(buf, sizeof buf, &used,
                   "%s{\"kind\":\"%s\",\"type\":%d,\"size\":%u,"
                   "\"flags\":%u,\"powered\":%s,\"force\":%.3f,"
                   "\"model\":%s%s%s}",
                   i ? "," : "", wsg_finger_kind_name(fs->f[i].kind),
                   (int)wsg_finger_type(fs, i),
                   (unsigned)wsg_finger_size(fs, i),
                   (unsigned)wsg_finger_flags(fs, i, faults),
                   fs->f[i].powered ? "true" : "false", fs->f[i].contact.force,
                   g->fdev[i] ? "\"" : "",
                   g->fdev[i] ? wsg_fdev_name(g->fdev[i]) : "null",
                   g->fdev[i] ? "\"" : "");
        append(buf, sizeof buf, &used, "]");
        reply(c, "ok %s", buf);
        return;
    }
    if ((strcmp(argv[1], "0") != 0 && strcmp(argv[1], "1") != 0) || argc < 3) {
        reply(c, "error usage: finger [0|1 none|generic|fmf|dsa|device "
                 "FILE|power on|off|cells]");
        return;
    }
    i = argv[1][0] - '0';
    if (argc == 3 && strcmp(argv[2], "cells") == 0) {
        append(buf, sizeof buf, &used, "[");
        for (k = 0; k < WSG_DSA_CELLS; k++)
            append(buf, sizeof buf, &used, "%s%u", k ? "," : "",
                   fs->f[i].kind == WSG_FINGER_DSA && fs->f[i].powered
                       ? (unsigned)fs->f[i].cells[k]
                       : 0u);
        append(buf, sizeof buf, &used, "]");
        reply(c, "ok %s", buf);
        return;
    }
    if (argc == 4 && strcmp(argv[2], "power") == 0) {
        int on = strcmp(argv[3], "on") == 0;

        if (!on && strcmp(argv[3], "off") != 0) {
            reply(c, "error usage: finger 0|1 power on|off");
            return;
        }
        if (fs->f[i].kind == WSG_FINGER_NONE) {
            reply(c, "error finger %d: no finger fitted", i);
            return;
        }
        wsg_finger_request_power(fs, i, on);
        wsg_device_settle(&g->dev);
        changed(c, "finger %d power %s", i, on ? "on" : "off");
        return;
    }
    k = wsg_finger_kind_parse(argv[2]);
    if (k < 0 || (k == WSG_FINGER_DEVICE) != (argc == 4) || argc > 4) {
        reply(c, "error usage: finger 0|1 none|generic|fmf|dsa|device FILE");
        return;
    }
    if (wsg_gripper_finger(g, i, k, argc == 4 ? argv[3] : NULL, err,
                           sizeof err) < 0) {
        reply(c, "error finger %d: %s", i, err);
        return;
    }
    if (k == WSG_FINGER_DEVICE)
        changed(c, "finger %d device %s", i, wsg_fdev_name(g->fdev[i]));
    else
        changed(c, "finger %d %s", i, argv[2]);
}

static void cmd_state(struct ctl_ctx *c, int argc, char **argv)
{
    char buf[WSG_STATE_JSON_MAX];

    (void)argc;
    (void)argv;
    wsg_state_format(buf, sizeof buf, c->ctl->cur, c->ctl->sched,
                     WSG_STATE_ALL);
    reply(c, "ok %s", buf);
}

static void cmd_drop(struct ctl_ctx *c, int argc, char **argv)
{
    (void)argc;
    (void)argv;
    struct wsg_gripper *g = c->ctl->cur;
    unsigned n = 0;
    size_t i;

    for (i = 0; i < g->ntransports; i++)
        if (g->transports[i].ops->drop_all)
            n += g->transports[i].ops->drop_all(&g->transports[i]);
    reply(c, "ok dropped %u", n);
}

static void cmd_reset(struct ctl_ctx *c, int argc, char **argv)
{
    (void)argc;
    (void)argv;
    /* Streams end with the power cycle (wsg_device_reset). */
    wsg_device_reset(&c->ctl->cur->dev);
    changed(c, "reset");
}

static void cmd_gripper(struct ctl_ctx *c, int argc, char **argv)
{
    const struct wsg_sched *l = c->ctl->sched;
    double v;

    if (argc > 2) {
        reply(c, "error usage: gripper [N]");
        return;
    }
    if (argc == 2) {
        if (!parse_num(argv[1], &v) || v < 0 || v != floor(v) ||
            v >= (double)l->ngrippers) {
            reply(c, "error gripper: N must be a gripper number in 0..%lu",
                  (unsigned long)l->ngrippers - 1ul);
            return;
        }
        c->s->gripper = (unsigned)v;
    }
    reply(c, "ok gripper %u of %lu", c->s->gripper,
          (unsigned long)l->ngrippers);
}

/* The loop's figures, for benchmarks and to see a fleet's state. */
static void cmd_stats(struct ctl_ctx *c, int argc, char **argv)
{
    (void)argc;
    (void)argv;
    const struct wsg_sched *l = c->ctl->sched;

    reply(c,
          "ok {\"grippers\":%lu,\"active\":%lu,\"steps\":%llu,"
          "\"gripper_steps\":%llu,\"overruns\":%llu,\"idle_steps\":%llu,"
          "\"wakes\":%llu,\"late_max_us\":%.1f,\"step_us\":%.0f,"
          "\"scale\":%g,\"paused\":%s}",
          (unsigned long)l->ngrippers, (unsigned long)wsg_sched_active(l),
          (unsigned long long)l->stats.steps,
          (unsigned long long)l->stats.dev_steps,
          (unsigned long long)l->stats.overruns,
          (unsigned long long)l->stats.idle_steps,
          (unsigned long long)l->stats.wakes,
          (double)l->stats.late_max_ns / 1000.0, (double)l->step_ns / 1000.0,
          l->scale, l->paused ? "true" : "false");
}

/* s as a JSON string (quotes included) at *used, cut to fit: the escapes
 * a JSON parser needs, control bytes as \u00XX, other bytes as they are
 * (a script prints UTF-8, or bytes a client shows as it can). Returns the
 * bytes of s taken. */
static size_t append_json(char *buf, size_t cap, size_t *used, const char *s,
                          size_t n)
{
    size_t i;

    if (*used + 2 >= cap)
        return 0;
    buf[(*used)++] = '"';
    for (i = 0; i < n; i++) {
        unsigned char ch = (unsigned char)s[i];
        char esc[8];
        size_t k;

        if (ch == '"' || ch == '\\')
            k = (size_t)snprintf(esc, sizeof esc, "\\%c", ch);
        else if (ch == '\n' || ch == '\t')
            k = (size_t)snprintf(esc, sizeof esc, "\\%c",
                                 ch == '\n' ? 'n' : 't');
        else if (ch < 0x20 || ch == 0x7F)
            k = (size_t)snprintf(esc, sizeof esc, "\\u%04x", ch);
        else
            k = (size_t)snprintf(esc, sizeof esc, "%c", ch);
        if (*used + k + 2 > cap)
            break;
        memcpy(buf + *used, esc, k);
        *used += k;
    }
    buf[(*used)++] = '"';
    buf[*used] = '\0';
    return i;
}

static const char *const script_states[] = {[WSG_SCRIPT_STOPPED] = "stopped",
                                            [WSG_SCRIPT_RUNNING] = "running",
                                            [WSG_SCRIPT_RUNNABLE] = "runnable",
                                            [WSG_SCRIPT_READING] = "reading",
                                            [WSG_SCRIPT_SLEEPING] =
                                                "sleeping"};

static void script_status(struct ctl_ctx *c, struct wsg_script *h)
{
    char buf[WSG_CTL_REPLY_MAX - 8];
    struct wsg_script_status st;
    uint8_t ids[256];
    size_t used = 0, n, i;

    wsg_script_status(h, &st);
    append(buf, sizeof buf, &used, "{\"running\":%s,\"failed\":%s,\"error\":",
           st.running ? "true" : "false", st.failed ? "true" : "false");
    if (st.error)
        append_json(buf, sizeof buf, &used, st.error, strlen(st.error));
    else
        append(buf, sizeof buf, &used, "null");
    append(buf, sizeof buf, &used, ",\"file\":");
    if (st.file)
        append_json(buf, sizeof buf, &used, st.file, strlen(st.file));
    else
        append(buf, sizeof buf, &used, "null");
    append(buf, sizeof buf, &used, ",\"state\":\"%s\",\"registered\":[",
           script_states[st.state]);
    n = wsg_script_registered(h, ids, sizeof ids);
    for (i = 0; i < n; i++)
        append(buf, sizeof buf, &used, "%s%u", i ? "," : "", (unsigned)ids[i]);
    append(buf, sizeof buf, &used,
           "],\"memory\":%lu,\"memory_max\":%lu,\"preempted\":%llu}",
           (unsigned long)st.memory, (unsigned long)st.memory_max,
           (unsigned long long)st.preempted);
    reply(c, "ok %s", buf);
}

/* What the script printed from byte FROM on, as much as one answer
 * holds: the client asks again from "next" until it reaches "end". */
static void script_output(struct ctl_ctx *c, struct wsg_script *h,
                          const char *from_text)
{
    char buf[WSG_CTL_REPLY_MAX - 8], text[1024];
    unsigned long from = 0;
    uint64_t start, end;
    size_t used = 0, n, took;

    if (from_text && wsg_parse_ulong(from_text, ULONG_MAX, &from) < 0) {
        reply(c, "error script output: FROM must be a byte offset");
        return;
    }
    start = wsg_script_output(h, from, text, sizeof text, &n, &end);
    append(buf, sizeof buf, &used,
           "{\"from\":%llu,\"lost\":%llu,\"text\":", (unsigned long long)start,
           (unsigned long long)(start > from ? start - from : 0));
    took = append_json(buf, sizeof buf - 64, &used, text, n);
    append(buf, sizeof buf, &used, ",\"next\":%llu,\"end\":%llu}",
           (unsigned long long)(start + took), (unsigned long long)end);
    reply(c, "ok %s", buf);
}

/* capture start FILE | stop | (status): the capture of every interface
 * (capture.h). FILE is opened by the daemon, relative to its directory. */
static void cmd_capture(struct ctl_ctx *c, int argc, char **argv)
{
    struct wsg_capture *cap = c->ctl->capture;

    if (!cap) {
        reply(c, "error capture: not available here");
        return;
    }
    if (argc == 3 && strcmp(argv[1], "start") == 0) {
        char err[WSG_CTL_LINE_MAX + 128];

        if (wsg_capture_start(cap, argv[2], err, sizeof err) < 0)
            reply(c, "error %s", err);
        else
            reply(c, "ok capture %s", cap->path);
    } else if (argc == 2 && strcmp(argv[1], "stop") == 0) {
        uint64_t n = cap->records;
        int was = cap->f != NULL;

        wsg_capture_stop(cap);
        if (was)
            reply(c, "ok capture stopped %llu records", (unsigned long long)n);
        else
            reply(c, "ok capture off");
    } else if (argc == 1) {
        if (!cap->f)
            reply(c, "ok capture off");
        else
            reply(c, "ok capture %s records %llu bytes %llu%s", cap->path,
                  (unsigned long long)cap->records,
                  (unsigned long long)cap->size, cap->full ? " stopped" : "");
    } else {
        reply(c, "error usage: capture [start FILE|stop]");
    }
}

static void cmd_script(struct ctl_ctx *c, int argc, char **argv)
{
    struct wsg_gripper *g = c->ctl->cur;
    struct wsg_script *h;
    char err[512];
    int r;

    if (argc < 2) {
        reply(c, "error usage: script run FILE | script stop | script status "
                 "| script output [FROM]");
        return;
    }
    if (wsg_gripper_script(g, &h) < 0) {
        reply(c, "error script: no memory for a script host");
        return;
    }
    if (strcmp(argv[1], "run") == 0 && argc == 3) {
        if (c->s->script_run)
            r = c->s->script_run(c->s->ctx, h, argv[2], err, sizeof err);
        else
            r = wsg_script_start(h, argv[2], err, sizeof err);
        if (r < 0)
            reply(c, "error script: %s", err);
        else
            reply(c, "ok script running %s", argv[2]);
    } else if (strcmp(argv[1], "stop") == 0 && argc == 2) {
        r = wsg_script_stop(h);
        reply(c, r < 0 ? "ok script not running" : "ok script stopped");
    } else if (strcmp(argv[1], "status") == 0 && argc == 2) {
        script_status(c, h);
    } else if (strcmp(argv[1], "output") == 0 && argc <= 3) {
        script_output(c, h, argc == 3 ? argv[2] : NULL);
    } else {
        reply(c, "error usage: script run FILE | script stop | script status "
                 "| script output [FROM]");
    }
}

static void run_command(struct ctl_ctx *c, int argc, char **argv);
static void cmd_help(struct ctl_ctx *c, int argc, char **argv);

static void run_line(struct ctl_ctx *c, char *line)
{
    char *argv[WSG_CTL_OBJECT_ARGS_MAX];
    int argc = 0, max = WSG_CTL_ARGS_MAX;
    char *p = line;

    for (;;) {
        while (*p == ' ' || *p == '\t' || *p == '\r')
            p++;
        if (!*p)
            break;
        if (argc == 1 && strcmp(argv[0], "object") == 0)
            max = WSG_CTL_OBJECT_ARGS_MAX;
        if (argc == max) {
            reply(c, "error too many arguments");
            return;
        }
        argv[argc++] = p;
        while (*p && *p != ' ' && *p != '\t' && *p != '\r')
            p++;
        if (*p)
            *p++ = '\0';
    }
    /* Every line gets its one answer, so a script that reads one line per
     * line it sent stays in step, even after a stray empty one. */
    if (argc == 0) {
        reply(c, "error empty line (try help)");
        return;
    }
    /* The selected gripper's time is brought up to the grid before the
     * command reads or changes it; afterwards it is stepped if it now has
     * work. Settled like a gripper command: a fault's consequences (FAST
     * STOP, a motion aborted) are there when "ok" is. */
    c->ctl->cur = &c->ctl->sched->grippers[c->s->gripper];
    wsg_sched_touch(c->ctl->sched, c->ctl->cur);
    run_command(c, argc, argv);
    wsg_device_settle(&c->ctl->cur->dev);
    wsg_sched_check(c->ctl->sched, c->ctl->cur);
}

/* The commands: name, what runs it, whether it takes arguments (the rest
 * are refused them here, once), and its form for help. */
static const struct ctl_command {
    const char *name;
    void (*run)(struct ctl_ctx *c, int argc, char **argv);
    int takes_args;
    const char *form;
} ctl_commands[] = {
    {"part", cmd_part, 1, "part WIDTH [STIFFNESS]|none"},
    {"obstacle", cmd_obstacle, 1, "obstacle WIDTH|none"},
    {"object", cmd_object, 1,
     "object box W D H|cylinder D L|sphere D [MASS [FRICTION]]|none"},
    {"pull", cmd_pull, 1, "pull N"},
    {"fault", cmd_fault, 1, "fault NAME on|off"},
    {"patch", cmd_patch, 1, "patch W H|default"},
    {"finger", cmd_finger, 1,
     "finger [0|1 none|generic|fmf|dsa|device FILE|power on|off|cells]"},
    {"time", cmd_time, 1, "time [scale X|pause|step MS|resume]"},
    {"state", cmd_state, 0, "state"},
    {"drop", cmd_drop, 0, "drop"},
    {"reset", cmd_reset, 0, "reset"},
    {"gripper", cmd_gripper, 1, "gripper [N]"},
    {"stats", cmd_stats, 0, "stats"},
    {"script", cmd_script, 1, "script run FILE|stop|status|output [FROM]"},
    {"capture", cmd_capture, 1, "capture [start FILE|stop]"},
    {"help", cmd_help, 0, NULL},
};

#define CTL_NCOMMANDS (sizeof ctl_commands / sizeof ctl_commands[0])

static void cmd_help(struct ctl_ctx *c, int argc, char **argv)
{
    char buf[WSG_CTL_REPLY_MAX - 8];
    size_t used = 0, i;

    (void)argc;
    (void)argv;
    buf[0] = '\0';
    for (i = 0; i < CTL_NCOMMANDS; i++)
        if (ctl_commands[i].form)
            append(buf, sizeof buf, &used, "%s%s", used ? ", " : "",
                   ctl_commands[i].form);
    reply(c, "ok commands: %s", buf);
}

static void run_command(struct ctl_ctx *c, int argc, char **argv)
{
    size_t i;

    for (i = 0; i < CTL_NCOMMANDS; i++) {
        const struct ctl_command *k = &ctl_commands[i];

        if (strcmp(argv[0], k->name) != 0)
            continue;
        if (argc > 1 && !k->takes_args)
            reply(c, "error %s takes no arguments", argv[0]);
        else
            k->run(c, argc, argv);
        return;
    }
    reply(c, "error unknown command '%.32s' (try help)", argv[0]);
}

void wsg_control_session_init(struct wsg_ctl_session *s,
                              void (*answer)(void *ctx, const char *line,
                                             size_t len),
                              void *ctx)
{
    memset(s, 0, sizeof *s);
    s->answer = answer;
    s->ctx = ctx;
}

void wsg_control_input(struct wsg_ctl *ctl, struct wsg_ctl_session *s,
                       const char *data, size_t n)
{
    struct ctl_ctx c;
    size_t i;

    c.ctl = ctl;
    c.s = s;
    for (i = 0; i < n && !s->closed; i++) {
        char ch = data[i];

        if (ch == '\n') {
            if (s->overlong)
                reply(&c, "error line longer than %u bytes", WSG_CTL_LINE_MAX);
            else {
                s->line[s->len] = '\0';
                run_line(&c, s->line);
            }
            s->len = 0;
            s->overlong = 0;
        } else if (s->overlong) {
            continue;
        } else if (s->len == WSG_CTL_LINE_MAX || ch == '\0') {
            /* A NUL would cut the line short unseen: treat as garbage. */
            s->overlong = 1;
        } else {
            s->line[s->len++] = ch;
        }
    }
}

/* A session's answers go out through the client's peer; once it is gone,
 * the lines it sent are not run. */
static void client_answer(void *ctx, const char *line, size_t len)
{
    struct wsg_ctl_client *c = ctx;

    if (!c->peer.dead)
        wsg_peer_send(&c->peer, (const uint8_t *)line, len);
    c->s.closed = c->peer.dead;
}

static void client_read(struct wsg_ctl_client *c)
{
    char buf[WSG_CTL_READ_CHUNK];
    ssize_t n;

    n = recv(c->peer.watch.fd, buf, sizeof buf, MSG_DONTWAIT);
    if (n > 0) {
        wsg_control_input(c->ctl, &c->s, buf, (size_t)n);
        return;
    }
    if (n == 0) {
        wsg_peer_kill(&c->peer, NULL);
        return;
    }
    if (errno == EINTR || errno == EAGAIN || errno == EWOULDBLOCK)
        return;
    wsg_peer_kill(&c->peer, errno == ECONNRESET ? NULL : strerror(errno));
}

static void client_event(struct wsg_watch *w, uint32_t events)
{
    struct wsg_peer *p = (struct wsg_peer *)w;

    /* Lines that came before a close are still answered (as far as the
     * peer still reads): "printf 'drop\n' | nc" must work. */
    if (wsg_peer_ready(p, events))
        client_read(client_of(p));
}

static void client_watch(struct wsg_watch *w, int fd, void *ctx)
{
    wsg_watch_init(w, fd, client_event, ctx);
}

static void on_listen(struct wsg_watch *w, uint32_t events)
{
    struct wsg_ctl *ctl = w->ctx;
    static const char full[] = "error too many control clients\n";
    struct wsg_peer *p;
    int fd;
    int r;

    (void)events;
    fd = accept4(ctl->watch.fd, NULL, NULL, SOCK_NONBLOCK | SOCK_CLOEXEC);
    if (fd < 0)
        return; /* EAGAIN, or a pending connection that failed */
    if (wsg_peer_full(&ctl->clients)) {
        /* Told why, rather than left to guess from a bare close. */
        if (send(fd, full, sizeof full - 1, MSG_NOSIGNAL) < 0)
            (void)0;
        close(fd);
        return;
    }
    r = wsg_peer_open(&ctl->clients, fd, NULL, &p);
    if (r < 0) {
        fprintf(stderr, "wsgemu: control: refused a client: %s\n",
                strerror(-r));
        close(fd);
        return;
    }
    client_of(p)->ctl = ctl;
    wsg_control_session_init(&client_of(p)->s, client_answer, client_of(p));
}

/* After each batch: free the clients that ended during it. */
static void ctl_reap(void *ctx)
{
    struct wsg_ctl *ctl = ctx;

    wsg_peer_reap(&ctl->clients);
}

int wsg_control_describe(const struct wsg_ctl *ctl, char *buf, size_t len)
{
    int r = snprintf(buf, len, "%s", ctl->local);

    return r < 0 || (size_t)r >= len ? -ENOSPC : 0;
}

void wsg_control_close(struct wsg_ctl *ctl)
{
    if (!ctl)
        return;
    wsg_reactor_forget(ctl->reactor, ctl_reap, ctl);
    wsg_peer_set_fini(&ctl->clients);
    if (ctl->watch.fd >= 0) {
        wsg_reactor_del(ctl->reactor, &ctl->watch);
        close(ctl->watch.fd);
    }
    free(ctl);
}

void wsg_control_set_capture(struct wsg_ctl *ctl, struct wsg_capture *cap)
{
    ctl->capture = cap;
}

int wsg_control_new(struct wsg_ctl **out, struct wsg_reactor *reactor,
                    struct wsg_sched *sched)
{
    struct wsg_ctl *ctl = calloc(1, sizeof *ctl);
    /* No generations (no sessions to tell apart), and a client dropped
     * for not reading is closed with a FIN, not reset. */
    const struct wsg_peer_config clients = {
        .size = sizeof(struct wsg_ctl_client),
        .offset = offsetof(struct wsg_ctl_client, peer),
        .max = WSG_CTL_CLIENTS_MAX,
        .log = "wsgemu: control: closing a client",
        .watch = client_watch,
        .ctx = ctl,
    };

    *out = NULL;
    if (!ctl)
        return -ENOMEM;
    ctl->reactor = reactor;
    ctl->sched = sched;
    ctl->watch.fd = -1;
    wsg_peer_set_init(&ctl->clients, reactor, &clients);
    *out = ctl;
    return 0;
}

int wsg_control_open(struct wsg_ctl **out, struct wsg_reactor *reactor,
                     struct wsg_sched *sched, const struct wsg_endpoint *ep,
                     char *err, size_t errlen)
{
    struct wsg_ctl *ctl;
    int r;

    r = wsg_control_new(&ctl, reactor, sched);
    if (r < 0) {
        snprintf(err, errlen, "cannot listen on control: %s", strerror(-r));
        return r;
    }
    r = wsg_transport_listen_tcp(ep, (int)WSG_CTL_CLIENTS_MAX, "control",
                                 ctl->local, sizeof ctl->local, err, errlen);
    if (r < 0)
        goto fail;
    wsg_watch_init(&ctl->watch, r, on_listen, ctl);
    r = wsg_reactor_add(reactor, &ctl->watch, EPOLLIN);
    if (r < 0) {
        snprintf(err, errlen, "cannot listen on control %s: epoll: %s",
                 ctl->local, strerror(-r));
        goto fail;
    }
    r = wsg_reactor_after(reactor, ctl_reap, ctl);
    if (r < 0) {
        snprintf(err, errlen, "cannot serve control %s: %s", ctl->local,
                 strerror(-r));
        goto fail;
    }
    *out = ctl;
    return 0;

fail:
    wsg_control_close(ctl);
    return r;
}
