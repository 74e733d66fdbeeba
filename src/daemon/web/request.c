/*
 * What a request carries, decoded and checked before a handler sees it:
 * its media type (Content-Type) matched exactly, its URL checked for
 * characters no name of the page may hold, and its form (a body of type
 * application/x-www-form-urlencoded) decoded into the request's fields.
 *
 * The page's names and values are C strings: a NUL decoded from "%00"
 * would cut "a.lua%00.txt" to "a.lua", a name the check before it never
 * saw. So a NUL or any other control character (0x00-0x1f, 0x7f), sent
 * raw or percent-encoded, in the URL's path or query or in a form's
 * names or values, refuses the request: no name or value of the page
 * holds one (a control command is one line, a setting a word, a number
 * or a path, a script name letters and digits).
 */
#include <errno.h>
#include <stdint.h>
#include <string.h>
#include <strings.h>

#include "impl.h"

static int is_control(unsigned char c)
{
    return c < 0x20 || c == 0x7f;
}

static int hex_value(char c)
{
    if (c >= '0' && c <= '9')
        return c - '0';
    if (c >= 'a' && c <= 'f')
        return c - 'a' + 10;
    if (c >= 'A' && c <= 'F')
        return c - 'A' + 10;
    return -1;
}

/* The byte "%XX" at s (n bytes left) stands for, or -1 when s is not
 * one: a '%' not followed by two hex digits is itself, as libmicrohttpd
 * decodes the URL. */
static int percent(const char *s, size_t n)
{
    int hi, lo;

    if (n < 3 || s[0] != '%')
        return -1;
    hi = hex_value(s[1]);
    lo = hex_value(s[2]);
    return hi < 0 || lo < 0 ? -1 : hi * 16 + lo;
}

int wsg_web_media_is(const char *value, const char *type)
{
    size_t n = strlen(type);

    if (!value)
        return 0;
    while (*value == ' ' || *value == '\t')
        value++;
    if (strncasecmp(value, type, n) != 0)
        return 0;
    value += n;
    /* The type ends there, or its parameters follow (";charset=..."):
     * "application/x-www-form-urlencodedXYZ" is another type. */
    while (*value == ' ' || *value == '\t')
        value++;
    return *value == '\0' || *value == ';';
}

int wsg_web_url_bad(const char *uri)
{
    size_t n = strlen(uri), i;
    int c;

    for (i = 0; i < n; i++) {
        c = percent(uri + i, n - i);
        if (c < 0)
            c = (unsigned char)uri[i];
        else
            i += 2;
        if (is_control((unsigned char)c))
            return 1;
    }
    return 0;
}

/* Decode the n bytes at in (a form's name or value: '+' is a space, %XX
 * a byte) into out, NUL-terminated: the length, -E2BIG when it does not
 * fit cap, -EILSEQ when it holds a control character. */
static int form_decode_part(const char *in, size_t n, char *out, size_t cap)
{
    size_t i, used = 0;
    int c;

    for (i = 0; i < n; i++) {
        c = percent(in + i, n - i);
        if (c >= 0)
            i += 2;
        else
            c = in[i] == '+' ? ' ' : (unsigned char)in[i];
        if (is_control((unsigned char)c))
            return -EILSEQ;
        if (used + 1 >= cap)
            return -E2BIG;
        out[used++] = (char)c;
    }
    out[used] = '\0';
    return (int)used;
}

int wsg_web_form_decode(struct wsg_web_req *req)
{
    const char *p = req->body, *end = req->body + req->body_len;
    struct wsg_web_field *f;
    const char *amp, *eq;
    int r;

    /* A pass over the body: each "name=value" (or "name") between '&'s,
     * at most WSG_WEB_FIELDS_MAX of them; empty ones are skipped. */
    for (; p < end; p = amp + 1) {
        amp = memchr(p, '&', (size_t)(end - p));
        if (!amp)
            amp = end;
        if (amp == p)
            continue;
        if (req->nfields == WSG_WEB_FIELDS_MAX)
            return -E2BIG;
        f = &req->fields[req->nfields];
        eq = memchr(p, '=', (size_t)(amp - p));
        r = form_decode_part(p, (size_t)((eq ? eq : amp) - p), f->name,
                             sizeof f->name);
        if (r >= 0)
            r = eq ? form_decode_part(eq + 1, (size_t)(amp - eq - 1), f->value,
                                      sizeof f->value)
                   : form_decode_part("", 0, f->value, sizeof f->value);
        if (r < 0)
            return r;
        req->nfields++;
    }
    return 0;
}
