/*
 * wsgctl --control: readings through the emulator's control channel
 * instead of the gripper's interface, so a tool can look while a driver
 * moves the gripper without disturbing it (no 07h, no session). The
 * channel's "state" line is put into the reply layout the gripper would
 * have sent, and printed as that.
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
