/*
 * wsgctl --control: the emulator's control channel. Readings through it
 * instead of the gripper's interface, so a tool can look while a driver
 * moves the gripper without disturbing it (no 07h, no session): the
 * channel's "state" line is put into the reply layout the gripper would
 * have sent, and printed as that. And the channel's scenario commands
 * (part, obstacle, object, pull, fault, time, drop, reset), sent as the line
 * they are and answered with what the channel answers; control_line is the one
 * exchange of a line they and the scripts (script.c) share.
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

/* A reading through the emulator's control channel ("state"), printed as
 * the gripper's answer would be. Nothing is sent to the gripper, so
 * nothing happens to it: no 07h at the close (which aborts a running
 * motion, 3.1.2), no session, no FAST STOP. */
int control_read(struct ctx *x, uint8_t id, const uint8_t *payload, size_t len)
{
    const struct wsg_layout *layout = &wsg_schema[id].reply;
    char line[2048];
    size_t np;
    double v[WSG_FIELDS_MAX];
    uint8_t p[WSG_REPLY_PARAMS_MAX];
    int ok = 1, r;

    /* Readings only: 42h's reset flag (stats --reset) changes the
     * gripper. */
    if (len && !(id == WSG_CMD_GET_GRASP_STATS && len == 1 && !payload[0])) {
        err("--control reads only: %02Xh %s with parameters changes the "
            "gripper",
            id, cmd_name(id));
        return EXIT_USAGE;
    }
    /* A reading answers numbers, which the channel's state may hold; not
     * nothing, not text. */
    if (layout->n == 0 || layout->fields[layout->n - 1].type == WSG_FT_TEXT ||
        layout->fields[layout->n - 1].type == WSG_FT_BYTES) {
        err("--control reads only: %02Xh %s is not a reading", id,
            cmd_name(id));
        return EXIT_USAGE;
    }
    r = wsg_client_line(&x->c.l, "state", line, sizeof line,
                        timeout_deadline(&x->o));
    if (r == 0) {
        err("control channel: no answer to \"state\"");
        return EXIT_CONN;
    }
    if (r < 0) {
        if (r == -EPIPE)
            err("control channel: closed");
        else
            err("control channel: %s", strerror(-r));
        return EXIT_CONN;
    }
    if (strncmp(line, "ok {", 4) != 0) {
        err("control channel: %s", line);
        return EXIT_CONN;
    }
    /* Each field of the reply under its name in the channel's spelling
     * ("no_part"), put on the wire as the gripper would send it. */
    for (size_t i = 0; ok && i < layout->n; i++) {
        char key[24]; /* with quotes and colon, fits wsg_json_num's 32 */

        wsg_schema_key(layout->fields[i].name, key, sizeof key);
        ok = wsg_json_num(line, key, v + i) == 0;
    }
    if (!ok) {
        err("control channel: unexpected state: %s", line);
        return EXIT_CONN;
    }
    np = wsg_layout_encode(layout, v, p);
    print_values(&x->o, "", id, p, np);
    return EXIT_OK;
}

/* One command line to the channel and its answer. The text after "ok "
 * into *rest and 0; an "error" answer is said as the emulator's reason
 * (exit 1: it refused, as a gripper answers an error status; exit 2 for
 * "error usage: ...", the channel's word for a malformed command), a dead
 * or silent channel as such (exit 3). */
int control_line(struct ctx *x, const char *cmd, char *line, size_t cap,
                 const char **rest)
{
    int r = wsg_client_line(&x->c.l, cmd, line, cap, timeout_deadline(&x->o));

    if (r == -EMSGSIZE) {
        err("the line \"%s\" is too long for the control channel", cmd);
        return EXIT_USAGE;
    }
    if (r == 0) {
        err("control channel: no answer to \"%s\"", cmd);
        return EXIT_CONN;
    }
    if (r < 0) {
        err("control channel: %s", r == -EPIPE ? "closed" : strerror(-r));
        return r == -EINTR ? EXIT_INTERRUPTED : EXIT_CONN;
    }
    if (!strncmp(line, "ok", 2) && (line[2] == ' ' || line[2] == '\0')) {
        *rest = line[2] ? line + 3 : line + 2;
        return EXIT_OK;
    }
    if (!strncmp(line, "error ", 6)) {
        err("%s", line + 6);
        return strncmp(line + 6, "usage:", 6) ? EXIT_GRIPPER : EXIT_USAGE;
    }
    err("control channel: unexpected answer: %s", line);
    return EXIT_CONN;
}

/* part, obstacle, object, pull, fault, time, drop, reset: the command line as
 * given (the name and its arguments, checked by the channel, which knows the
 * gripper's range), and the answer without its "ok" ("part 40 50",
 * "paused", "dropped 1"); with --json under "answer". */
int c_channel(struct ctx *x, int argc, char **argv)
{
    char cmd[256], line[2048];
    const char *rest;
    size_t used;
    int rc;

    used = (size_t)snprintf(cmd, sizeof cmd, "%s", x->command);
    for (int i = 0; i < argc; i++) {
        /* The channel splits its lines at blanks: an argument with one
         * would become two. */
        if (!argv[i][0] || strpbrk(argv[i], " \t\r\n")) {
            err("%s: an argument cannot be empty or hold a blank: \"%s\"",
                x->command, argv[i]);
            return EXIT_USAGE;
        }
        used += (size_t)snprintf(cmd + used,
                                 used < sizeof cmd ? sizeof cmd - used : 0,
                                 " %s", argv[i]);
    }
    if (used >= sizeof cmd) {
        err("%s: arguments too long", x->command);
        return EXIT_USAGE;
    }
    rc = control_line(x, cmd, line, sizeof line, &rest);
    if (rc)
        return rc;
    if (x->o.jo)
        jout_str(x->o.jo, "answer", rest, strlen(rest));
    else if (rest[0])
        puts(rest);
    return EXIT_OK;
}

/* capture start FILE, stop, or its state: the channel's own command, with
 * FILE absolute (wsgctl_path) so that it lands where the user meant. */
int c_capture(struct ctx *x, int argc, char **argv)
{
    char path[4096];
    char *args[2];
    int rc;

    if (argc == 0 || strcmp(argv[0], "stop") == 0)
        return c_channel(x, argc, argv);
    if (strcmp(argv[0], "start") != 0 || argc != 2) {
        err("capture: start FILE, stop, or nothing (its state)");
        return EXIT_USAGE;
    }
    rc = wsgctl_path("capture start", argv[1], path, sizeof path);
    if (rc)
        return rc;
    args[0] = argv[0];
    args[1] = path;
    return c_channel(x, 2, args);
}
