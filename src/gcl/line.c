/*
 * GCL's line codec: bytes into lines, and a line into a command. Like the
 * binary frame parser it consumes input incrementally into state the
 * caller owns (one read may hold several lines or half of one), and a line
 * it cannot take (too long, binary bytes) is reported once, at its
 * newline, where the next line starts afresh. No I/O, no clock, no
 * allocation.
 */
#include <ctype.h>
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "wsg/gcl.h"

void wsg_gcl_line_init(struct wsg_gcl_line *l)
{
    memset(l, 0, sizeof *l);
}

/* Bytes a text line holds: printable ASCII, tabs, and a CR (before the
 * LF of clients that end lines with CR LF, or anywhere: it counts as a
 * blank). */
static int text_byte(uint8_t b)
{
    return (b >= 0x20 && b < 0x7F) || b == '\t' || b == '\r';
}

size_t wsg_gcl_line_feed(struct wsg_gcl_line *l, const uint8_t *data,
                         size_t len, enum wsg_gcl_event *ev, const char **line,
                         size_t *n)
{
    size_t i;

    *ev = WSG_GCL_NONE;
    for (i = 0; i < len; i++) {
        uint8_t b = data[i];

        if (b != '\n') {
            if (!text_byte(b))
                l->binary = 1;
            /* One byte of room past the limit: the CR of a line of the
             * limit's length that ends in CR LF. */
            if (l->len == WSG_GCL_LINE_MAX + 1)
                l->overlong = 1;
            else if (!l->overlong)
                l->buf[l->len++] = (char)b;
            continue;
        }
        /* CR LF: the CR is not part of the line. */
        while (l->len > 0 && l->buf[l->len - 1] == '\r')
            l->len--;
        if (l->len > WSG_GCL_LINE_MAX)
            l->overlong = 1;
        if (l->overlong)
            *ev = WSG_GCL_TOO_LONG;
        else if (l->binary)
            *ev = WSG_GCL_BINARY;
        else if (l->len > 0)
            *ev = WSG_GCL_LINE;
        l->buf[l->len] = '\0';
        *line = l->buf;
        *n = l->len;
        l->len = 0;
        l->overlong = 0;
        l->binary = 0;
        if (*ev != WSG_GCL_NONE)
            return i + 1;
    }
    return len;
}

static const char *skip_blanks(const char *p, const char *end)
{
    while (p < end && (*p == ' ' || *p == '\t' || *p == '\r'))
        p++;
    return p;
}

/* One value: a number, "text", or true/false. Returns the position after
 * it, or NULL. */
static const char *parse_value(const char *p, const char *end,
                               struct wsg_gcl_arg *a)
{
    char num[64];
    size_t k;
    char *stop;

    memset(a, 0, sizeof *a);
    if (p < end && *p == '"') {
        for (p++, k = 0; p < end && *p != '"'; p++) {
            if (k == WSG_GCL_STR_MAX)
                return NULL;
            a->str[k++] = *p;
        }
        if (p == end)
            return NULL;
        a->is_str = 1;
        return p + 1;
    }
    for (k = 0; p + k < end && k < sizeof num - 1 &&
                (isalnum((unsigned char)p[k]) || p[k] == '.' || p[k] == '-' ||
                 p[k] == '+');
         k++)
        num[k] = p[k];
    num[k] = '\0';
    if (k == 0)
        return NULL;
    if (strcmp(num, "true") == 0 || strcmp(num, "TRUE") == 0) {
        a->num = 1.0;
        return p + k;
    }
    if (strcmp(num, "false") == 0 || strcmp(num, "FALSE") == 0) {
        a->num = 0.0;
        return p + k;
    }
    errno = 0;
    a->num = strtod(num, &stop);
    /* The whole token, a finite number: "1e999", "nan", "0x10" are not. */
    if (*stop != '\0' || errno != 0 || !isfinite(a->num) ||
        strpbrk(num, "xXnN") != NULL)
        return NULL;
    return p + k;
}

int wsg_gcl_parse(const char *line, size_t n, struct wsg_gcl_cmd *c)
{
    const char *p = line, *end = line + n;
    size_t k = 0;

    memset(c, 0, sizeof *c);
    c->index = -1;
    p = skip_blanks(p, end);
    if (p == end || !isalpha((unsigned char)*p))
        return -1;
    while (p < end && (isalnum((unsigned char)*p) || *p == '_')) {
        if (k == WSG_GCL_NAME_MAX)
            return -1;
        c->name[k++] = (char)toupper((unsigned char)*p++);
    }
    p = skip_blanks(p, end);
    if (p == end)
        return -1;
    switch (*p) {
    case '(':
        c->form = WSG_GCL_CALL;
        p = skip_blanks(p + 1, end);
        if (p < end && *p == ')') {
            p++;
            break;
        }
        for (;;) {
            if (c->nargs == WSG_GCL_ARGS_MAX)
                return -1;
            p = parse_value(skip_blanks(p, end), end, &c->arg[c->nargs++]);
            if (!p)
                return -1;
            p = skip_blanks(p, end);
            if (p < end && *p == ',') {
                p++;
                continue;
            }
            if (p < end && *p == ')') {
                p++;
                break;
            }
            return -1;
        }
        break;
    case '[': {
        /* Digits by hand: strtol would read past n on "FDATA[1". */
        const char *q = p + 1;
        int i = 0;

        for (; q < end && *q >= '0' && *q <= '9'; q++) {
            i = i * 10 + (*q - '0');
            if (i > 255)
                return -1;
        }
        if (q == p + 1 || q == end || *q != ']')
            return -1;
        c->index = i;
        p = skip_blanks(q + 1, end);
        if (p == end || *p != '?')
            return -1;
        c->form = WSG_GCL_QUERY;
        p++;
        break;
    }
    case '?':
        c->form = WSG_GCL_QUERY;
        p++;
        break;
    case '=':
        c->form = WSG_GCL_SET;
        p = parse_value(skip_blanks(p + 1, end), end, &c->arg[0]);
        if (!p)
            return -1;
        c->nargs = 1;
        break;
    default:
        return -1;
    }
    return skip_blanks(p, end) == end ? 0 : -1;
}

size_t wsg_gcl_line_vformat(char *buf, size_t cap, const char *fmt, va_list ap)
{
    int n = vsnprintf(buf, cap - 1, fmt, ap);

    if (n < 0)
        return 0;
    if ((size_t)n > cap - 2)
        n = (int)(cap - 2);
    buf[n++] = '\n';
    return (size_t)n;
}
