/*
 * A client of the daemon's control channel (--control) for the tests:
 * lines over TCP to the address of the ready line's control= field, read
 * by the client library's line client (wsgclient.h).
 */
#ifndef WSG_TEST_EMU_CTL_H
#define WSG_TEST_EMU_CTL_H

#include <stddef.h>

#include "emu.h"

/* The client library's line client over TCP. */
struct ctl {
    struct wsg_client link;
};

/* Connect to control= of e's ready line. 0 or -1. */
int ctl_open(struct ctl *c, const struct emu *e);
void ctl_close(struct ctl *c);
int ctl_write(struct ctl *c, const char *s);
/* The next line (without its newline) into out; 0, or -1 on timeout or
 * end of stream. */
int ctl_line(struct ctl *c, char *out, size_t cap);
/* Send one command line and read its answer (valid until the next call). */
const char *ctl_cmd(struct ctl *c, const char *cmd);
/* "ok" or "ok ...". CMD_OK below needs check.h at its use. */
int ctl_is_ok(const char *ans);
/* "ok S.FFFFFF" -> microseconds, exactly; -1 if it is not that. */
long long ctl_time_us(const char *ans);
/* The number after "key": in a JSON answer; -1e9 when absent. */
double ctl_json_num(const char *json, const char *key);

#define CMD_OK(c, cmd)                                                        \
    do {                                                                      \
        const char *ans_ = ctl_cmd((c), (cmd));                               \
        if (!ctl_is_ok(ans_))                                                 \
            fprintf(stderr, "%s -> %s\n", (cmd), ans_);                       \
        CHECK(ctl_is_ok(ans_));                                               \
    } while (0)

#endif
