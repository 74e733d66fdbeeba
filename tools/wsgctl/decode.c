/*
 * wsgctl's printing of what the gripper says: values by the schema's
 * reply layouts ("width 55.00 mm", or bare with --quiet), hex bytes,
 * command names and error statuses; and the decode command, which reads
 * hex dumps of packets from stdin and says what each one is: request or
 * reply, its status, its checksum, its values.
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

/* The parameters of a successful answer with this ID, by the schema's
 * reply layout: one line per field, "width 55.00 mm", "grasp-state 4
 * (HOLDING)", each after indent; with --quiet, the bare values on one
 * line ("55.00", "1 1 2.2.0 1"). Returns 1 if they fit the layout and
 * there are any, else 0 (nothing printed). */
int print_values(const struct opts *o, const char *indent, uint8_t id,
                 const uint8_t *p, size_t n)
{
    static const struct wsg_value_style human = {2, " (", " ", ")", 0, 0};
    static const struct wsg_value_style bare = {2, "", "", "", 1, 0};
    struct wsg_value v[WSG_FIELDS_MAX];
    char buf[4 * WSG_REPLY_PARAMS_MAX + 64];
    int k = wsg_layout_decode(&wsg_schema[id].reply, p, n, v);

    if (k <= 0)
        return 0;
    if (o->jo) {
        for (int i = 0; i < k; i++)
            jout_value(o->jo, &v[i]);
        return 1;
    }
    for (int i = 0; i < k; i++) {
        const char *unit = v[i].field->unit;

        wsg_value_format(&v[i], o->quiet ? &bare : &human, buf, sizeof buf);
        if (o->quiet)
            printf("%s%s", i ? " " : indent, buf);
        else
            printf("%s%s %s%s%s\n", indent, v[i].field->name, buf,
                   unit[0] ? " " : "", unit);
    }
    if (o->quiet)
        putchar('\n');
    return 1;
}

void print_hex(const uint8_t *p, size_t n)
{
    for (size_t i = 0; i < n; i++)
        printf("%s%02X", i ? " " : "", p[i]);
}

const char *cmd_name(uint8_t id)
{
    const char *n = wsg_cmd_name(id);

    return n ? n : "(unknown ID)";
}

/* Report an error status; the exit status for it. */
int gripper_error(uint8_t id, unsigned status)
{
    err("%02Xh %s: %s", id, cmd_name(id), wsg_status_name(status));
    return EXIT_GRIPPER;
}

/* Hex bytes from text: tokens separated by whitespace or commas, each
 * optionally "0x"-prefixed or "h"-suffixed; a token of several byte pairs
 * ("AAAAAA20") is split. Returns the count, or -1 on a bad token. */
static long read_hex(FILE *in, uint8_t *buf, size_t cap)
{
    char tok[1024];
    size_t n = 0, tl = 0;
    int ch;

    do {
        ch = fgetc(in);
        if (ch != EOF && ch != ',' && ch != ' ' && ch != '\t' && ch != '\n' &&
            ch != '\r' && ch != ';') {
            if (tl + 1 >= sizeof tok)
                return -1;
            tok[tl++] = (char)ch;
            continue;
        }
        if (tl == 0)
            continue;
        tok[tl] = '\0';
        char *t = tok;
        if (t[0] == '0' && (t[1] == 'x' || t[1] == 'X'))
            t += 2;
        size_t len = strlen(t);
        if (len && (t[len - 1] == 'h' || t[len - 1] == 'H'))
            t[--len] = '\0';
        if (len == 1) {
            t[1] = t[0];
            t[0] = '0';
            t[2] = '\0';
            len = 2;
        }
        if (len == 0 || len % 2)
            return -1;
        for (size_t i = 0; i < len; i += 2) {
            char pair[3] = {t[i], t[i + 1], '\0'};
            char *end;
            unsigned long v = strtoul(pair, &end, 16);
            if (*end != '\0' || pair[0] == '+' || pair[0] == '-' || n >= cap)
                return -1;
            buf[n++] = (uint8_t)v;
        }
        tl = 0;
    } while (ch != EOF);
    return (long)n;
}

/* The payload leads with a status the manual names. */
static int leads_with_status(const uint8_t *payload, size_t size)
{
    return size >= 2 &&
           strcmp(wsg_status_name(wsg_get_u16(payload)), "E_UNKNOWN") != 0;
}

/* Could this payload be a reply to ID? A status the manual names first;
 * with E_SUCCESS, the parameters that ID returns. */
static int reply_fits(uint8_t id, const uint8_t *payload, size_t size)
{
    if (!leads_with_status(payload, size))
        return 0;
    if (wsg_get_u16(payload) != WSG_E_SUCCESS)
        return size == 2;
    return wsg_cmd_name(id) != NULL &&
           wsg_layout_fits(&wsg_schema[id].reply, size - 2u);
}

/* "request", "reply", or both where the bytes fit either (a Loop, a
 * Set Device Tag of two bytes); by the length rules of the command table
 * and the reply shapes of the manual. */
static const char *direction(uint8_t id, const uint8_t *payload, size_t size)
{
    int req = wsg_cmd_request_fits(id, size);
    int rep = reply_fits(id, payload, size);

    if (req && rep)
        return "request or reply";
    if (rep)
        return "reply";
    if (req)
        return "request";
    /* Neither: a request the gripper refuses by its length (or an ID it
     * does not know), unless it leads with a status. */
    return leads_with_status(payload, size)
               ? "reply (unexpected length)"
               : "request (refused by its length or ID)";
}

int c_decode(struct ctx *x, int argc, char **argv)
{
    const size_t cap = 1u << 20; /* 1 MiB of packets is plenty */
    uint8_t *buf = malloc(cap);
    long total;
    size_t i = 0, packets = 0;
    int bad = 0;

    (void)argc;
    (void)argv;
    if (!buf) {
        err("decode: out of memory");
        return EXIT_CONN;
    }
    total = read_hex(stdin, buf, cap);
    if (total < 0) {
        err("decode: input is not hex bytes (or over 1 MiB)");
        free(buf);
        return EXIT_USAGE;
    }
    while (i < (size_t)total) {
        /* Hunt for the preamble; a longer run of AA extends it. */
        if (i + 3 > (size_t)total || buf[i] != 0xAA || buf[i + 1] != 0xAA ||
            buf[i + 2] != 0xAA) {
            size_t skip = i;
            while (i < (size_t)total &&
                   !(i + 3 <= (size_t)total && buf[i] == 0xAA &&
                     buf[i + 1] == 0xAA && buf[i + 2] == 0xAA))
                i++;
            printf("skipped %zu bytes before a preamble\n", i - skip);
            bad = 1;
            continue;
        }
        size_t start = i;
        i += 3;
        while (i < (size_t)total && buf[i] == 0xAA)
            i++;
        /* Let the CRC run over a three-byte preamble, as sent. */
        start = i - 3;
        if (i + 3 > (size_t)total) {
            printf("incomplete packet at the end (%zu bytes)\n",
                   (size_t)total - start);
            bad = 1;
            break;
        }
        uint8_t id = buf[i];
        uint16_t size = wsg_get_u16(buf + i + 1);
        size_t end = i + 3 + size + 2;
        if (end > (size_t)total) {
            printf("%02Xh %s SIZE %u: incomplete (%zu of %zu bytes)\n", id,
                   cmd_name(id), size, (size_t)total - start, end - start);
            bad = 1;
            break;
        }
        const uint8_t *payload = buf + i + 3;
        int ok = wsg_crc_update(WSG_CRC_INIT, buf + start, end - start) == 0;
        const char *dir = direction(id, payload, size);
        int is_reply = strncmp(dir, "reply", 5) == 0;
        packets++;
        printf("%s %02Xh %s SIZE %u", dir, id, cmd_name(id), size);
        if (strcmp(dir, "request") != 0 && leads_with_status(payload, size))
            printf(" status %s", wsg_status_name(wsg_get_u16(payload)));
        printf(" payload%s", size ? " " : "");
        print_hex(payload, size);
        printf(" checksum %02X %02X %s\n", buf[end - 2], buf[end - 1],
               ok ? "ok" : "bad");
        if (!ok)
            bad = 1;
        /* A reply's success: its values too, indented. */
        if (ok && is_reply && wsg_get_u16(payload) == WSG_E_SUCCESS &&
            size > 2) {
            struct opts o = x->o;
            o.quiet = 0;
            if (!print_values(&o, "  ", id, payload + 2, size - 2u))
                printf("  (no decoded values)\n");
        }
        i = end;
    }
    free(buf);
    if (packets == 0 && !bad) {
        printf("no packets\n");
        bad = 1;
    }
    return bad ? EXIT_GRIPPER : EXIT_OK;
}
