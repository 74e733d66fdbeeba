/*
 * The control channel's client for the integration tests: one command
 * line out, one answer line back, every wait bounded by EMU_REPLY_MS.
 */
#include "emu_ctl.h"

#include <arpa/inet.h>
#include <netinet/in.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

int ctl_open(struct ctl *c, const struct emu *e)
{
    char v[64];
    struct sockaddr_in sa;

    wsg_client_init(&c->link, WSG_LINK_TCP);
    if (!emu_field(e, "control", v, sizeof v) || emu_ipv4_addr(v, &sa) < 0)
        return -1;
    return wsg_client_open_tcp(&c->link, &sa, EMU_REPLY_MS) < 0 ? -1 : 0;
}

void ctl_close(struct ctl *c)
{
    wsg_client_close(&c->link);
}

int ctl_write(struct ctl *c, const char *s)
{
    return wsg_client_line_send(&c->link, s) < 0 ? -1 : 0;
}

int ctl_line(struct ctl *c, char *out, size_t cap)
{
    return wsg_client_line_read(&c->link, out, cap,
                                wsg_client_deadline(EMU_REPLY_MS)) == 1
               ? 0
               : -1;
}

/* Send one command line and read its answer. */
const char *ctl_cmd(struct ctl *c, const char *cmd)
{
    static char line[4096]; /* the test is single-threaded */
    char out[512];

    snprintf(out, sizeof out, "%s\n", cmd);
    if (ctl_write(c, out) < 0 || ctl_line(c, line, sizeof line) < 0)
        return "(no answer)";
    return line;
}

int ctl_is_ok(const char *ans)
{
    return strncmp(ans, "ok", 2) == 0 && (ans[2] == '\0' || ans[2] == ' ');
}

/* "ok S.FFFFFF" -> microseconds, exactly; -1 if it is not that. */
long long ctl_time_us(const char *ans)
{
    char *end;
    long long s, f = 0;
    int digits = 0;

    if (strncmp(ans, "ok ", 3) != 0)
        return -1;
    s = strtoll(ans + 3, &end, 10);
    if (*end == '.') {
        for (end++; *end >= '0' && *end <= '9'; end++, digits++)
            f = f * 10 + (*end - '0');
    }
    if (*end != '\0' || digits > 6)
        return -1;
    while (digits++ < 6)
        f *= 10;
    return s * 1000000 + f;
}

double ctl_json_num(const char *json, const char *key)
{
    char pat[64];
    const char *p;

    snprintf(pat, sizeof pat, "\"%s\":", key);
    p = strstr(json, pat);
    return p ? strtod(p + strlen(pat), NULL) : -1e9;
}
