/*
 * The web page's Host and Origin rules (web_host.h). Everything here reads
 * text a browser or an attacker wrote, so each function takes an explicit
 * length, reads nothing past it, and accepts only what its grammar says:
 * a name is compared whole, never as a prefix, and a number is decimal
 * digits only (strtoul would take signs, blanks, hex and octal).
 */
#include "web_host.h"

#include <errno.h>
#include <string.h>

static int is_digit(char c)
{
    return c >= '0' && c <= '9';
}

static char lower(char c)
{
    return c >= 'A' && c <= 'Z' ? (char)(c - 'A' + 'a') : c;
}

/* a (n bytes) and the string b are the same but for case. */
static int same_name(const char *a, size_t n, const char *b)
{
    size_t i;

    for (i = 0; i < n; i++)
        if (b[i] == '\0' || lower(a[i]) != lower(b[i]))
            return 0;
    return b[n] == '\0';
}

int wsg_web_host_split(const char *value, size_t len, const char **host,
                       size_t *host_len, unsigned *port)
{
    const char *close, *colon;
    size_t n, i;
    unsigned long v = 0;

    if (len == 0)
        return -EINVAL;
    if (value[0] == '[') {
        close = memchr(value, ']', len);
        if (!close)
            return -EINVAL;
        n = (size_t)(close - value) + 1;
    } else {
        colon = memchr(value, ':', len);
        n = colon ? (size_t)(colon - value) : len;
    }
    if (n == 0)
        return -EINVAL;
    *host = value;
    *host_len = n;
    *port = 0;
    if (n == len)
        return 0;
    /* ":PORT": 1..5 digits, 1..65535, and the end. */
    if (value[n] != ':' || len - n - 1 == 0 || len - n - 1 > 5)
        return -EINVAL;
    for (i = n + 1; i < len; i++) {
        if (!is_digit(value[i]))
            return -EINVAL;
        v = v * 10 + (unsigned long)(value[i] - '0');
    }
    if (v == 0 || v > 65535)
        return -EINVAL;
    *port = (unsigned)v;
    return 0;
}

int wsg_web_host_ipv4(const char *s, size_t n, uint8_t addr[4])
{
    size_t i = 0;
    int part;

    for (part = 0; part < 4; part++) {
        size_t start = i;
        unsigned v = 0;

        if (part > 0) {
            if (i >= n || s[i] != '.')
                return -EINVAL;
            start = ++i;
        }
        while (i < n && is_digit(s[i]) && i - start < 3)
            v = v * 10 + (unsigned)(s[i++] - '0');
        /* 1..3 digits, no leading zero (0177 would be octal to some
         * readers), at most 255. */
        if (i == start || (s[start] == '0' && i - start > 1) || v > 255)
            return -EINVAL;
        addr[part] = (uint8_t)v;
    }
    return i == n ? 0 : -EINVAL;
}

int wsg_web_host_loopback(const char *host, size_t n)
{
    uint8_t a[4];

    if (wsg_web_host_ipv4(host, n, a) == 0)
        return a[0] == 127;
    return same_name(host, n, "localhost") || same_name(host, n, "[::1]");
}

/* A DNS name: labels of letters, digits and inner hyphens, 1..63 each. */
static int dns_name(const char *s, size_t n)
{
    size_t i, label = 0;

    if (n == 0 || n > WSG_WEB_HOST_NAME_MAX)
        return 0;
    for (i = 0; i < n; i++) {
        char c = s[i];

        if (c == '.') {
            if (label == 0 || s[i - 1] == '-')
                return 0;
            label = 0;
        } else if (is_digit(c) || (lower(c) >= 'a' && lower(c) <= 'z') ||
                   (c == '-' && label > 0)) {
            if (++label > 63)
                return 0;
        } else {
            return 0;
        }
    }
    return label > 0 && s[n - 1] != '-';
}

int wsg_web_host_name_valid(const char *name, size_t n)
{
    uint8_t a[4];
    size_t i;

    if (n >= 4 && name[0] == '[' && name[n - 1] == ']') {
        int colons = 0;

        if (n > 2 + 45) /* the longest IPv6 text */
            return -EINVAL;
        for (i = 1; i + 1 < n; i++) {
            char c = lower(name[i]);

            if (c == ':')
                colons++;
            else if (!is_digit(c) && !(c >= 'a' && c <= 'f') && c != '.')
                return -EINVAL;
        }
        return colons >= 2 ? 0 : -EINVAL;
    }
    if (wsg_web_host_ipv4(name, n, a) == 0)
        return 0;
    /* All digits and dots but no IPv4 literal (256.1.1.1, 1.2.3): a
     * browser would read it as a number, not as this name. */
    for (i = 0; i < n; i++)
        if (!is_digit(name[i]) && name[i] != '.')
            break;
    if (i == n)
        return -EINVAL;
    return dns_name(name, n) ? 0 : -EINVAL;
}

/* host (n bytes, no port) is one of the page's names. */
static int host_known(const char *host, size_t n, const char *allow,
                      const uint8_t bound[4])
{
    uint8_t a[4];
    const char *p, *comma;

    if (wsg_web_host_loopback(host, n))
        return 1;
    if (bound && (bound[0] | bound[1] | bound[2] | bound[3]) &&
        wsg_web_host_ipv4(host, n, a) == 0 && memcmp(a, bound, 4) == 0)
        return 1;
    for (p = allow; p && *p; p = comma ? comma + 1 : p + strlen(p)) {
        size_t k;

        comma = strchr(p, ',');
        k = comma ? (size_t)(comma - p) : strlen(p);
        if (k == n) {
            size_t i;

            for (i = 0; i < n && lower(host[i]) == lower(p[i]); i++)
                ;
            if (i == n)
                return 1;
        }
    }
    return 0;
}

int wsg_web_host_allowed(const char *value, const char *allow,
                         const uint8_t bound[4])
{
    const char *host;
    size_t n;
    unsigned port;

    if (!value ||
        wsg_web_host_split(value, strlen(value), &host, &n, &port) < 0)
        return 0;
    return host_known(host, n, allow, bound);
}

int wsg_web_origin_allowed(const char *origin, const char *host,
                           const char *allow, const uint8_t bound[4])
{
    static const char scheme[] = "http://";
    const char *oh, *hh;
    size_t on, hn, i;
    unsigned op, hp;

    if (!origin)
        return 1;
    if (!host || strncmp(origin, scheme, sizeof scheme - 1) != 0)
        return 0;
    origin += sizeof scheme - 1;
    if (wsg_web_host_split(origin, strlen(origin), &oh, &on, &op) < 0 ||
        wsg_web_host_split(host, strlen(host), &hh, &hn, &hp) < 0 ||
        !host_known(oh, on, allow, bound))
        return 0;
    /* The page's own origin: the same host and port as the request's
     * Host (the page's requests carry both), 80 when left out. */
    if (on != hn || (op ? op : 80u) != (hp ? hp : 80u))
        return 0;
    for (i = 0; i < on; i++)
        if (lower(oh[i]) != lower(hh[i]))
            return 0;
    return 1;
}
