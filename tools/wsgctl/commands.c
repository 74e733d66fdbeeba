/*
 * wsgctl's commands that send one request (or two) and print the answer:
 * motions, readings, settings, loop, bye, and raw, which sends a packet
 * written in WSG Commander's command-editor syntax. Arguments in human
 * units are checked here; what is printed is decode.c's.
 */
#define _GNU_SOURCE /* getaddrinfo, sigaction, localtime_r */

#include "wsgctl.h"

#include <errno.h>
#include <netdb.h>
#include <netinet/in.h>
#include <signal.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/socket.h>
#include <time.h>
#include <unistd.h>

/* A request whose success answer is printed with print_values (or
 * nothing). E_NOT_AVAILABLE on an optional setting (soft limits, tag)
 * prints "none" and is no error when none_ok. */
static int simple(struct ctx *x, uint8_t id, const uint8_t *payload,
                  size_t len, int none_ok)
{
    struct wsg_client_frame r;
    int rc;

    if (x->c.kind == LINK_CONTROL)
        return control_read(x, id, payload, len);
    rc = xact(x, id, payload, len, &r, NULL);
    if (rc)
        return rc;
    if (none_ok && r.status == WSG_E_NOT_AVAILABLE) {
        if (x->o.jo) {
            /* Not set is no error: null under the reading's key. */
            x->o.jo->status = WSG_E_SUCCESS;
            jout_add(x->o.jo, ",\"%s\":null",
                     id == WSG_CMD_GET_DEVICE_TAG ? "tag" : "soft_limits");
        } else {
            printf(x->o.quiet ? "none\n" : "%s none\n", x->command);
        }
        return EXIT_OK;
    }
    if (r.status != WSG_E_SUCCESS)
        return gripper_error(id, r.status);
    print_values(&x->o, "", id, WSG_CLIENT_PARAMS(&r), WSG_CLIENT_NPARAMS(&r));
    return EXIT_OK;
}

static int need_float(const char *what, const char *s, float *v)
{
    if (parse_float(s, v) < 0) {
        err("%s: not a number: \"%s\"", what, s);
        return EXIT_USAGE;
    }
    return 0;
}

int c_home(struct ctx *x, int argc, char **argv)
{
    uint8_t dir = 0;

    if (argc == 1) {
        if (!strcmp(argv[0], "pos"))
            dir = 1;
        else if (!strcmp(argv[0], "neg"))
            dir = 2;
        else {
            err("home: direction is pos or neg, not \"%s\"", argv[0]);
            return EXIT_USAGE;
        }
    }
    return simple(x, WSG_CMD_HOMING, &dir, 1, 0);
}

/* move, grasp, release: WIDTH SPEED. */
static int width_speed(struct ctx *x, uint8_t id, char **argv)
{
    uint8_t pl[9], *q = pl;
    float w, s;

    if (need_float("width", argv[0], &w) || need_float("speed", argv[1], &s))
        return EXIT_USAGE;
    if (id == WSG_CMD_PREPOSITION)
        *q++ =
            (uint8_t)((x->o.relative ? 1 : 0) | (x->o.stop_on_block ? 2 : 0));
    wsg_put_f32(q, w);
    wsg_put_f32(q + 4, s);
    return simple(x, id, pl, (size_t)(q + 8 - pl), 0);
}

int c_move(struct ctx *x, int argc, char **argv)
{
    (void)argc;
    return width_speed(x, WSG_CMD_PREPOSITION, argv);
}

int c_grasp(struct ctx *x, int argc, char **argv)
{
    (void)argc;
    return width_speed(x, WSG_CMD_GRASP, argv);
}

int c_release(struct ctx *x, int argc, char **argv)
{
    (void)argc;
    return width_speed(x, WSG_CMD_RELEASE, argv);
}

int c_stop(struct ctx *x, int argc, char **argv)
{
    (void)argc;
    (void)argv;
    return simple(x, WSG_CMD_STOP, NULL, 0, 0);
}

int c_fast_stop(struct ctx *x, int argc, char **argv)
{
    (void)argc;
    (void)argv;
    return simple(x, WSG_CMD_FAST_STOP, NULL, 0, 0);
}

int c_ack(struct ctx *x, int argc, char **argv)
{
    (void)argc;
    (void)argv;
    return simple(x, WSG_CMD_ACK_FAST_STOP, (const uint8_t *)"ack", 3, 0);
}

int c_info(struct ctx *x, int argc, char **argv)
{
    (void)argc;
    (void)argv;
    return simple(x, WSG_CMD_GET_SYSTEM_INFO, NULL, 0, 0);
}

int c_limits(struct ctx *x, int argc, char **argv)
{
    (void)argc;
    (void)argv;
    return simple(x, WSG_CMD_GET_SYSTEM_LIMITS, NULL, 0, 0);
}

int c_state(struct ctx *x, int argc, char **argv)
{
    int rc;

    (void)argc;
    (void)argv;
    rc = simple(x, WSG_CMD_GET_SYSTEM_STATE, NULL, 0, 0);
    return rc ? rc : simple(x, WSG_CMD_GET_GRASP_STATE, NULL, 0, 0);
}

int c_width(struct ctx *x, int argc, char **argv)
{
    (void)argc;
    (void)argv;
    return simple(x, WSG_CMD_GET_WIDTH, NULL, 0, 0);
}

int c_speed(struct ctx *x, int argc, char **argv)
{
    (void)argc;
    (void)argv;
    return simple(x, WSG_CMD_GET_SPEED, NULL, 0, 0);
}

int c_force(struct ctx *x, int argc, char **argv)
{
    (void)argc;
    (void)argv;
    return simple(x, WSG_CMD_GET_FORCE, NULL, 0, 0);
}

int c_temperature(struct ctx *x, int argc, char **argv)
{
    (void)argc;
    (void)argv;
    return simple(x, WSG_CMD_GET_TEMPERATURE, NULL, 0, 0);
}

int c_tag(struct ctx *x, int argc, char **argv)
{
    if (argc == 0)
        return simple(x, WSG_CMD_GET_DEVICE_TAG, NULL, 0, 1);
    return simple(x, WSG_CMD_SET_DEVICE_TAG, (const uint8_t *)argv[0],
                  strlen(argv[0]), 0);
}

/* acc, force-limit: get without a value, set with one. */
static int get_set(struct ctx *x, uint8_t get, uint8_t set, int argc,
                   char **argv)
{
    uint8_t pl[4];
    float v;

    if (argc == 0)
        return simple(x, get, NULL, 0, 0);
    if (need_float("value", argv[0], &v))
        return EXIT_USAGE;
    wsg_put_f32(pl, v);
    return simple(x, set, pl, 4, 0);
}

int c_acc(struct ctx *x, int argc, char **argv)
{
    return get_set(x, WSG_CMD_GET_ACCELERATION, WSG_CMD_SET_ACCELERATION, argc,
                   argv);
}

int c_force_limit(struct ctx *x, int argc, char **argv)
{
    return get_set(x, WSG_CMD_GET_FORCE_LIMIT, WSG_CMD_SET_FORCE_LIMIT, argc,
                   argv);
}

int c_soft_limits(struct ctx *x, int argc, char **argv)
{
    uint8_t pl[8];
    float minus, plus;

    if (argc == 0)
        return simple(x, WSG_CMD_GET_SOFT_LIMITS, NULL, 0, 1);
    if (argc == 1) {
        if (strcmp(argv[0], "clear") != 0) {
            err("soft-limits: MINUS PLUS, or clear");
            return EXIT_USAGE;
        }
        return simple(x, WSG_CMD_CLEAR_SOFT_LIMITS, NULL, 0, 0);
    }
    if (need_float("minus", argv[0], &minus) ||
        need_float("plus", argv[1], &plus))
        return EXIT_USAGE;
    wsg_put_f32(pl, minus);
    wsg_put_f32(pl + 4, plus);
    return simple(x, WSG_CMD_SET_SOFT_LIMITS, pl, 8, 0);
}

int c_overdrive(struct ctx *x, int argc, char **argv)
{
    uint8_t on;

    (void)argc;
    if (!strcmp(argv[0], "on"))
        on = 1;
    else if (!strcmp(argv[0], "off"))
        on = 0;
    else {
        err("overdrive: on or off, not \"%s\"", argv[0]);
        return EXIT_USAGE;
    }
    return simple(x, WSG_CMD_OVERDRIVE, &on, 1, 0);
}

int c_stats(struct ctx *x, int argc, char **argv)
{
    uint8_t flags = x->o.reset ? 1 : 0;

    (void)argc;
    (void)argv;
    return simple(x, WSG_CMD_GET_GRASP_STATS, &flags, 1, 0);
}

int c_loop(struct ctx *x, int argc, char **argv)
{
    struct wsg_client_frame r;
    size_t n = strlen(argv[0]);
    int rc;

    (void)argc;
    if (n > WSG_PAYLOAD_MAX) {
        err("loop: at most %u bytes", WSG_PAYLOAD_MAX);
        return EXIT_USAGE;
    }
    rc = xact(x, WSG_CMD_LOOP, (const uint8_t *)argv[0], n, &r, NULL);
    if (rc)
        return rc;
    if (r.status != WSG_E_SUCCESS)
        return gripper_error(WSG_CMD_LOOP, r.status);
    /* The echo comes back as status plus data, the data being ours. */
    if (x->o.jo)
        jout_str(x->o.jo, "echo", (const char *)WSG_CLIENT_PARAMS(&r),
                 WSG_CLIENT_NPARAMS(&r));
    else
        printf("%.*s\n", (int)WSG_CLIENT_NPARAMS(&r),
               (const char *)WSG_CLIENT_PARAMS(&r));
    return EXIT_OK;
}

int c_tare(struct ctx *x, int argc, char **argv)
{
    (void)argc;
    (void)argv;
    return simple(x, WSG_CMD_TARE, NULL, 0, 0);
}

int c_bye(struct ctx *x, int argc, char **argv)
{
    int rc;

    (void)argc;
    (void)argv;
    rc = simple(x, WSG_CMD_DISCONNECT, NULL, 0, 0);
    x->c.announced = 1; /* even if refused: a second one would be too */
    return rc;
}

/* ---- raw ---- */

/* One item of WSG Commander's command editor: a byte (32, 0x20), a float
 * (150.0f), or a string in double quotes ("text", one shell argument that
 * contains the quotes). Appends to buf; -1 on a bad item. */
static int raw_item(const char *s, uint8_t *buf, size_t cap, size_t *n)
{
    size_t len = strlen(s);
    unsigned long b;

    if (len >= 2 && s[0] == '"' && s[len - 1] == '"') {
        if (*n + len - 2 > cap)
            return -1;
        memcpy(buf + *n, s + 1, len - 2);
        *n += len - 2;
        return 0;
    }
    if (len >= 2 && (s[len - 1] == 'f' || s[len - 1] == 'F') &&
        strncmp(s, "0x", 2) != 0 && strncmp(s, "0X", 2) != 0) {
        char tmp[64];
        float v;
        if (len >= sizeof tmp)
            return -1;
        memcpy(tmp, s, len - 1);
        tmp[len - 1] = '\0';
        if (parse_float(tmp, &v) < 0 || *n + 4 > cap)
            return -1;
        wsg_put_f32(buf + *n, v);
        *n += 4;
        return 0;
    }
    if (parse_ulong(s, 255, &b) < 0 || *n + 1 > cap)
        return -1;
    buf[(*n)++] = (uint8_t)b;
    return 0;
}

/* "06h Loop: E_SUCCESS" and the parameters, for raw and decode. */
static void print_reply(const struct opts *o, const struct wsg_client_frame *r)
{
    printf("%02Xh %s: %s\n", r->id, cmd_name(r->id),
           wsg_status_name(r->status));
    printf("params (%zu):%s", WSG_CLIENT_NPARAMS(r),
           WSG_CLIENT_NPARAMS(r) ? " " : "");
    print_hex(WSG_CLIENT_PARAMS(r), WSG_CLIENT_NPARAMS(r));
    putchar('\n');
    if (r->status == WSG_E_SUCCESS)
        print_values(o, "", r->id, WSG_CLIENT_PARAMS(r),
                     WSG_CLIENT_NPARAMS(r));
}

int c_raw(struct ctx *x, int argc, char **argv)
{
    uint8_t pl[WSG_PAYLOAD_MAX];
    size_t n = 0;
    unsigned long id;
    struct wsg_client_frame r;
    int rc;

    if (parse_ulong(argv[0], 255, &id) < 0) {
        err("raw: bad ID \"%s\" (a byte: 32 or 0x20)", argv[0]);
        return EXIT_USAGE;
    }
    for (int i = 1; i < argc; i++) {
        if (raw_item(argv[i], pl, sizeof pl, &n) < 0) {
            err("raw: bad item \"%s\" (byte 32 or 0x20, float 150.0f, "
                "string '\"text\"'), or more than %u bytes",
                argv[i], WSG_PAYLOAD_MAX);
            return EXIT_USAGE;
        }
    }
    rc = xact(x, (uint8_t)id, pl, n, &r, x->o.jo ? NULL : print_reply);
    if (rc)
        return rc;
    if (x->o.jo) {
        /* The final answer: its ID, its parameters in hex as printed,
         * the values of a known ID. */
        char hex[3 * WSG_REPLY_PARAMS_MAX + 1];
        size_t np = WSG_CLIENT_NPARAMS(&r), k = 0;

        for (size_t i = 0; i < np && k + 4 <= sizeof hex; i++)
            k += (size_t)snprintf(hex + k, sizeof hex - k, "%s%02X",
                                  i ? " " : "", WSG_CLIENT_PARAMS(&r)[i]);
        hex[k] = '\0';
        jout_add(x->o.jo, ",\"id\":%u", r.id);
        jout_str(x->o.jo, "params", hex, k);
        if (r.status == WSG_E_SUCCESS)
            print_values(&x->o, "", r.id, WSG_CLIENT_PARAMS(&r), np);
    } else {
        print_reply(&x->o, &r);
    }
    return r.status == WSG_E_SUCCESS ? EXIT_OK : gripper_error(r.id, r.status);
}

/* finger I info|flags|data|power on|off over the gripper's interface:
 * the 4.x style, one block per finger (60h..63h for finger 0, 70h..73h
 * for finger 1; docs/fingers.md), decoded by the schema's reply rows.
 * Through --control the line goes to the channel as it is (its `finger`
 * reads both, fits a kind, switches power, reads a DSA frame). */
int c_finger(struct ctx *x, int argc, char **argv)
{
    static const char *const what[] = {"info", "flags", "power", "data"};
    uint8_t base, on;
    int k;

    if (x->c.kind == LINK_CONTROL)
        return c_channel(x, argc, argv);
    if (argc < 2 || (strcmp(argv[0], "0") != 0 && strcmp(argv[0], "1") != 0)) {
        err("finger: 0|1 info|flags|data|power on|off (a kind: with "
            "--control)");
        return EXIT_USAGE;
    }
    base = argv[0][0] == '0' ? 0x60 : 0x70;
    for (k = 0; k < 4 && strcmp(argv[1], what[k]) != 0; k++)
        ;
    if (k == 4) {
        err("finger: %s is not info, flags, data or power (a kind: with "
            "--control)",
            argv[1]);
        return EXIT_USAGE;
    }
    if (k != 2) {
        if (argc != 2) {
            err("finger: %s takes no value", argv[1]);
            return EXIT_USAGE;
        }
        return simple(x, (uint8_t)(base + k), NULL, 0, 0);
    }
    if (argc != 3 || (strcmp(argv[2], "on") != 0 && strcmp(argv[2], "off"))) {
        err("finger: power on|off");
        return EXIT_USAGE;
    }
    on = strcmp(argv[2], "on") == 0;
    return simple(x, (uint8_t)(base + 2), &on, 1, 0);
}
