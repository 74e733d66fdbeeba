/*
 * Command line parsing for wsgemu. Every option is validated here, before
 * anything is opened, so a typo ends the program with status 2 and one clear
 * line instead of a half-started emulator. Values land in struct
 * wsg_options; the model's configuration is resolved here too, because an
 * unknown model name is a usage error like any other.
 */
#define _GNU_SOURCE

#include "options.h"

#include <arpa/inet.h>
#include <errno.h>
#include <getopt.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

enum {
    OPT_TCP = 256,
    OPT_UDP,
    OPT_PTY,
    OPT_CAN,
    OPT_NO_CRC,
    OPT_NO_DISCONNECT_FAST_STOP,
    OPT_STEP_US,
    OPT_MODEL
};

static const struct option long_options[] = {
    {"tcp", required_argument, NULL, OPT_TCP},
    {"udp", required_argument, NULL, OPT_UDP},
    {"pty", required_argument, NULL, OPT_PTY},
    {"can", required_argument, NULL, OPT_CAN},
    {"no-crc", no_argument, NULL, OPT_NO_CRC},
    {"no-disconnect-fast-stop", no_argument, NULL,
     OPT_NO_DISCONNECT_FAST_STOP},
    {"step-us", required_argument, NULL, OPT_STEP_US},
    {"model", required_argument, NULL, OPT_MODEL},
    {"help", no_argument, NULL, 'h'},
    {NULL, 0, NULL, 0}};

static void usage(FILE *f)
{
    fprintf(
        f,
        "Usage: wsgemu [OPTION]...\n"
        "Emulate a Weiss WSG 50 gripper on its host interfaces.\n"
        "\n"
        "Interfaces (with none of these: TCP and UDP on their defaults):\n"
        "  --tcp [ADDR:]PORT          listen for TCP clients on an IPv4\n"
        "                             address (default 127.0.0.1:1000;\n"
        "                             port 0 picks a free port)\n"
        "  --udp [ADDR:]PORT[:REMOTE] receive datagrams on PORT, answer\n"
        "                             to the sender's address at port\n"
        "                             REMOTE (default 127.0.0.1:1500:1501)\n"
        "  --pty PATH                 serial port: a pseudo-terminal\n"
        "                             whose slave PATH links to\n"
        "  --can IFACE[:ID]           SocketCAN interface; commands on\n"
        "                             the 11-bit ID (default 0x000),\n"
        "                             answers on ID+1\n"
        "\n"
        "Gripper:\n"
        "  --no-crc                   ignore the checksums of received\n"
        "                             packets\n"
        "  --no-disconnect-fast-stop  no FAST STOP when a TCP client\n"
        "                             closes without a Disconnect\n"
        "                             Announcement (07h)\n"
        "  --step-us US               model step in microseconds\n"
        "                             (%u..%u, default %u)\n"
        "  --model NAME               wsg50 (default), wsg50-210, wsg32,\n"
        "                             wsg25\n"
        "  -h, --help                 show this help and exit\n"
        "\n"
        "When every interface is open, one line is printed on stdout:\n"
        "  ready tcp=ADDR:PORT udp=ADDR:PORT>REMOTE pty=PATH can=IFACE:ID\n"
        "(the fields of the open interfaces only).\n"
        "SIGINT or SIGTERM stops the emulator with exit status 0.\n",
        WSG_STEP_US_MIN, WSG_STEP_US_MAX, WSG_STEP_US_DEFAULT);
}

static void opt_error(const char *fmt, const char *arg)
{
    fputs("wsgemu: ", stderr);
    fprintf(stderr, fmt, arg);
    fputs(" (try --help)\n", stderr);
}

/* Decimal digits only: strtoul would also take signs, spaces and hex. */
static int parse_uint(const char *s, unsigned long max, unsigned long *out)
{
    unsigned long v = 0;

    if (*s == '\0')
        return -EINVAL;
    for (; *s; s++) {
        if (*s < '0' || *s > '9')
            return -EINVAL;
        v = v * 10 + (unsigned long)(*s - '0');
        if (v > max)
            return -ERANGE;
    }
    *out = v;
    return 0;
}

static int parse_endpoint(const char *arg, struct wsg_endpoint *ep)
{
    const char *colon = strrchr(arg, ':');
    const char *port = arg;
    unsigned long v;
    struct in_addr in;

    if (colon) {
        char host[INET_ADDRSTRLEN];
        size_t n = (size_t)(colon - arg);

        if (n == 0 || n >= sizeof host)
            return -EINVAL;
        memcpy(host, arg, n);
        host[n] = '\0';
        if (inet_pton(AF_INET, host, &in) != 1)
            return -EINVAL;
        memcpy(ep->addr, &in.s_addr, 4);
        port = colon + 1;
    }
    if (parse_uint(port, 65535, &v) < 0)
        return -EINVAL;
    ep->port = (uint16_t)v;
    return 0;
}

/* [ADDR:]PORT[:REMOTE]: an IPv4 ADDR has dots, so "1500:1501" is a port
 * pair and "127.0.0.1:1500" an address and a port. */
static int parse_udp(const char *arg, struct wsg_endpoint *ep,
                     uint16_t *remote)
{
    char buf[64];
    char *last = NULL;
    const char *first_colon = strchr(arg, ':');
    unsigned long v;
    int colons = 0;
    const char *p;

    if (strlen(arg) >= sizeof buf)
        return -EINVAL;
    for (p = arg; *p; p++)
        colons += *p == ':';
    strcpy(buf, arg);
    if (colons == 2 || (colons == 1 && first_colon &&
                        !memchr(arg, '.', (size_t)(first_colon - arg)))) {
        last = strrchr(buf, ':');
        *last++ = '\0';
        if (parse_uint(last, 65535, &v) < 0 || v == 0)
            return -EINVAL;
        *remote = (uint16_t)v;
    }
    return parse_endpoint(buf, ep);
}

/* IFACE[:ID], ID decimal or 0x-prefixed hex, 0..0x7FE. */
static int parse_can(char *arg, const char **iface, uint16_t *id)
{
    char *colon = strrchr(arg, ':');
    unsigned long v;
    char *end;

    if (colon) {
        *colon = '\0';
        if (colon[1] == '\0' || colon[1] == '-' || colon[1] == '+')
            return -EINVAL;
        errno = 0;
        v = strtoul(colon + 1, &end, 0);
        if (errno || *end || v > WSG_CAN_ID_MAX)
            return -EINVAL;
        *id = (uint16_t)v;
    }
    /* IFNAMSIZ is 16 with its NUL */
    if (arg[0] == '\0' || strlen(arg) > 15)
        return -EINVAL;
    *iface = arg;
    return 0;
}

void wsg_options_defaults(struct wsg_options *o)
{
    memset(o, 0, sizeof *o);
    o->tcp.addr[0] = 127;
    o->tcp.addr[3] = 1;
    o->tcp.port = WSG_TCP_PORT_DEFAULT;
    o->udp.addr[0] = 127;
    o->udp.addr[3] = 1;
    o->udp.port = WSG_UDP_PORT_DEFAULT;
    o->udp_remote_port = WSG_UDP_REMOTE_DEFAULT;
    o->can_id = WSG_CAN_ID_DEFAULT;
    o->control.addr[0] = 127;
    o->control.addr[3] = 1;
    o->time_scale = 1.0;
    o->initial_part = -1.0;
    o->serial = 1;
    o->check_crc = 1;
    o->disconnect_fast_stop = 1;
    o->step_us = WSG_STEP_US_DEFAULT;
    o->model = NULL;
}

enum wsg_options_result wsg_options_parse(struct wsg_options *o, int argc,
                                          char **argv)
{
    int c;
    unsigned long v;

    /* getopt's own messages would name argv[0], which may be a path; ours
     * always start with "wsgemu:". */
    opterr = 0;
    optind = 1;
    while ((c = getopt_long(argc, argv, ":h", long_options, NULL)) != -1) {
        switch (c) {
        case OPT_TCP:
            if (parse_endpoint(optarg, &o->tcp) < 0) {
                opt_error("--tcp: '%s' is not [ADDR:]PORT with an IPv4 ADDR "
                          "and a PORT of 0..65535",
                          optarg);
                return WSG_OPTIONS_ERROR;
            }
            o->tcp_enabled = 1;
            break;
        case OPT_UDP:
            if (parse_udp(optarg, &o->udp, &o->udp_remote_port) < 0) {
                opt_error("--udp: '%s' is not [ADDR:]PORT[:REMOTE] with an "
                          "IPv4 ADDR, a PORT of 0..65535 and a REMOTE port "
                          "of 1..65535",
                          optarg);
                return WSG_OPTIONS_ERROR;
            }
            o->udp_enabled = 1;
            break;
        case OPT_PTY:
            if (optarg[0] == '\0') {
                opt_error("--pty: '%s' is not a path", optarg);
                return WSG_OPTIONS_ERROR;
            }
            o->pty_path = optarg;
            break;
        case OPT_CAN:
            if (parse_can(optarg, &o->can_iface, &o->can_id) < 0) {
                opt_error("--can: '%s' is not IFACE[:ID] with an interface "
                          "name and an 11-bit ID of 0..0x7FE",
                          optarg);
                return WSG_OPTIONS_ERROR;
            }
            break;
        case OPT_NO_CRC:
            o->check_crc = 0;
            break;
        case OPT_NO_DISCONNECT_FAST_STOP:
            o->disconnect_fast_stop = 0;
            break;
        case OPT_STEP_US:
            if (parse_uint(optarg, WSG_STEP_US_MAX, &v) < 0 ||
                v < WSG_STEP_US_MIN) {
                opt_error("--step-us: '%s' is not a number of microseconds "
                          "in 100..100000",
                          optarg);
                return WSG_OPTIONS_ERROR;
            }
            o->step_us = (uint32_t)v;
            break;
        case OPT_MODEL:
            o->model = optarg;
            break;
        case 'h':
            usage(stdout);
            return WSG_OPTIONS_EXIT;
        case ':':
            opt_error("option '%s' needs an argument", argv[optind - 1]);
            return WSG_OPTIONS_ERROR;
        default: {
            const char *bad = argv[optind - 1];
            char opt[3] = {'-', (char)optopt, '\0'};

            /* optopt is 0 for an unknown long option and the option's
             * value for a known one given an argument it does not take. */
            if (strncmp(bad, "--", 2) == 0 && optopt != 0)
                opt_error("option '%s' takes no argument", bad);
            else if (strncmp(bad, "--", 2) == 0 || optopt <= 0 || optopt > 255)
                opt_error("unknown option '%s'", bad);
            else
                opt_error("unknown option '%s'", opt);
            return WSG_OPTIONS_ERROR;
        }
        }
    }
    if (optind < argc) {
        opt_error("unexpected argument '%s'", argv[optind]);
        return WSG_OPTIONS_ERROR;
    }
    if (!o->tcp_enabled && !o->udp_enabled && !o->pty_path && !o->can_iface)
        o->tcp_enabled = o->udp_enabled = 1;
    if (wsg_axis_config_init(&o->axis, o->model ? o->model : "wsg50") < 0) {
        opt_error("--model: unknown model '%s' (known: wsg50, wsg50-210, "
                  "wsg32, wsg25)",
                  o->model);
        return WSG_OPTIONS_ERROR;
    }
    o->axis.step_us = o->step_us;
    return WSG_OPTIONS_RUN;
}
