/*
 * The tests' HTTP client (emu_http.h). Connections are blocking sockets
 * read under poll() with a deadline; the chunked decoder works on what
 * has arrived and leaves a chunk that is not whole for the next read.
 */
#define _GNU_SOURCE

#include "emu_http.h"

#include <arpa/inet.h>
#include <ctype.h>
#include <errno.h>
#include <netinet/in.h>
#include <poll.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <sys/socket.h>
#include <unistd.h>

#include "emu.h"

/* The source address of the connections made from now on ("" or NULL:
 * the system's choice). */
static char source[INET_ADDRSTRLEN];

void http_source(const char *ip)
{
    snprintf(source, sizeof source, "%s", ip ? ip : "");
}

int http_open(const char *addr)
{
    struct sockaddr_in sa, from;
    int fd;

    if (emu_ipv4_addr(addr, &sa) < 0)
        return -1;
    fd = socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0);
    if (fd < 0)
        return -1;
    if (source[0]) {
        memset(&from, 0, sizeof from);
        from.sin_family = AF_INET;
        if (inet_pton(AF_INET, source, &from.sin_addr) != 1 ||
            bind(fd, (struct sockaddr *)&from, sizeof from) < 0) {
            fprintf(stderr, "http: bind %s: %s\n", source, strerror(errno));
            close(fd);
            return -1;
        }
    }
    if (connect(fd, (struct sockaddr *)&sa, sizeof sa) < 0) {
        fprintf(stderr, "http: connect %s: %s\n", addr, strerror(errno));
        close(fd);
        return -1;
    }
    return fd;
}

static int send_all(int fd, const char *p, size_t n)
{
    while (n > 0) {
        ssize_t w = send(fd, p, n, MSG_NOSIGNAL);

        if (w < 0 && errno == EINTR)
            continue;
        if (w <= 0)
            return -1;
        p += w;
        n -= (size_t)w;
    }
    return 0;
}

/* One read within the time left until deadline (emu_now_ms() clock).
 * Bytes read, 0 at the end, -1 on timeout, -2 on error. */
static long read_some(int fd, char *buf, size_t cap, double deadline)
{
    struct pollfd pfd = {fd, POLLIN, 0};
    double left = deadline - emu_now_ms();
    ssize_t n;
    int r;

    if (cap == 0)
        return -2;
    r = poll(&pfd, 1, left > 0 ? (int)left + 1 : 0);
    if (r == 0)
        return -1;
    if (r < 0)
        return errno == EINTR ? -1 : -2;
    n = recv(fd, buf, cap, 0);
    if (n < 0)
        return errno == EINTR ? -1 : -2;
    return (long)n;
}

/* Take the whole chunks of raw into text. -1 on a malformed chunk. */
static int dechunk(char *raw, size_t *raw_len, char *text, size_t *text_len,
                   size_t text_cap, int *eof)
{
    size_t pos = 0;

    for (;;) {
        char *end = memmem(raw + pos, *raw_len - pos, "\r\n", 2);
        unsigned long size;
        char *stop;

        if (!end)
            break;
        size = strtoul(raw + pos, &stop, 16);
        if (stop == raw + pos)
            return -1;
        if ((size_t)(end + 2 - raw) + size + 2 > *raw_len)
            break; /* not whole yet */
        if (size == 0) {
            *eof = 1;
            pos = (size_t)(end + 2 - raw) + 2;
            break;
        }
        if (*text_len + size >= text_cap)
            return -1;
        memcpy(text + *text_len, end + 2, size);
        *text_len += size;
        pos = (size_t)(end + 2 - raw) + size + 2;
    }
    memmove(raw, raw + pos, *raw_len - pos);
    *raw_len -= pos;
    return 0;
}

/* The end of the head in buf (the blank line), or NULL. */
static char *head_end(char *buf, size_t len)
{
    char *e = memmem(buf, len, "\r\n\r\n", 4);

    return e ? e + 4 : NULL;
}

/* The value of header name in head (a status line and header lines). */
static const char *find_header(const char *head, const char *name, char *buf,
                               size_t cap)
{
    const char *p = strstr(head, "\r\n");
    size_t n = strlen(name);

    while (p && p[2] != '\r' && p[2] != '\0') {
        const char *line = p + 2, *eol = strstr(line, "\r\n");

        if (!eol)
            break;
        if (strncasecmp(line, name, n) == 0 && line[n] == ':') {
            const char *v = line + n + 1;
            size_t len;

            while (*v == ' ')
                v++;
            len = (size_t)(eol - v) < cap - 1 ? (size_t)(eol - v) : cap - 1;
            memcpy(buf, v, len);
            buf[len] = '\0';
            return buf;
        }
        p = eol;
    }
    return NULL;
}

const char *http_header(const struct http_answer *a, const char *name,
                        char *buf, size_t cap)
{
    return find_header(a->head, name, buf, cap);
}

static int is_chunked(const char *head)
{
    char v[64];

    return find_header(head, "Transfer-Encoding", v, sizeof v) &&
           strcasecmp(v, "chunked") == 0;
}

/* Send head and body (len and blen bytes) on a connection of its own,
 * and read the answer to its end. */
static int http_exchange_parts(const char *addr, const char *head, size_t len,
                               const char *body, size_t blen,
                               struct http_answer *a, int timeout_ms)
{
    static char buf[HTTP_HEAD_MAX + 2 * HTTP_BODY_MAX];
    double deadline = emu_now_ms() + timeout_ms;
    size_t got = 0, hlen, rest;
    char *he;
    int fd, eof = 0;

    memset(a, 0, sizeof *a);
    fd = http_open(addr);
    if (fd < 0)
        return -1;
    if (send_all(fd, head, len) < 0 ||
        (blen && send_all(fd, body, blen) < 0)) {
        fprintf(stderr, "http: %.*s: send failed\n", (int)strcspn(head, "\r"),
                head);
        close(fd);
        return -1;
    }
    for (;;) {
        long r = read_some(fd, buf + got, sizeof buf - 1 - got, deadline);

        if (r == 0)
            break;
        if (r < 0) {
            fprintf(stderr, "http: %.*s: %s\n", (int)strcspn(head, "\r"), head,
                    r == -1 ? "timeout" : "read failed");
            close(fd);
            return -1;
        }
        got += (size_t)r;
    }
    close(fd);
    buf[got] = '\0';
    he = head_end(buf, got);
    if (!he || sscanf(buf, "HTTP/1.%*d %d", &a->status) != 1) {
        fprintf(stderr, "http: %.*s: no HTTP answer\n",
                (int)strcspn(head, "\r"), head);
        return -1;
    }
    hlen = (size_t)(he - buf);
    if (hlen >= sizeof a->head)
        return -1;
    memcpy(a->head, buf, hlen);
    a->head[hlen] = '\0';
    rest = got - hlen;
    if (is_chunked(a->head)) {
        if (dechunk(he, &rest, a->body, &a->body_len, sizeof a->body, &eof) <
                0 ||
            !eof) {
            fprintf(stderr, "http: %.*s: bad chunked body\n",
                    (int)strcspn(head, "\r"), head);
            return -1;
        }
    } else {
        if (rest >= sizeof a->body)
            return -1;
        memcpy(a->body, he, rest);
        a->body_len = rest;
    }
    a->body[a->body_len] = '\0';
    return 0;
}

int http_request(const char *addr, const char *method, const char *path,
                 const char *headers, const char *body, struct http_answer *a,
                 int timeout_ms)
{
    char req[HTTP_HEAD_MAX];
    int n;

    /* headers may name the Host themselves (a test of the Host check). */
    n = snprintf(
        req, sizeof req, "%s %s HTTP/1.1\r\n%s%s%sConnection: close\r\n%s",
        method, path,
        headers && strncasecmp(headers, "Host:", 5) == 0 ? "" : "Host: ",
        headers && strncasecmp(headers, "Host:", 5) == 0 ? "" : addr,
        headers && strncasecmp(headers, "Host:", 5) == 0 ? "" : "\r\n",
        headers ? headers : "");
    if (body)
        n += snprintf(req + n, sizeof req - (size_t)n,
                      "Content-Length: %zu\r\n", strlen(body));
    n += snprintf(req + n, sizeof req - (size_t)n, "\r\n");
    if (n < 0 || (size_t)n >= sizeof req)
        return -1;
    return http_exchange_parts(addr, req, (size_t)n, body,
                               body ? strlen(body) : 0, a, timeout_ms);
}

int http_exchange(const char *addr, const void *req, size_t len,
                  struct http_answer *a, int timeout_ms)
{
    return http_exchange_parts(addr, (const char *)req, len, NULL, 0, a,
                               timeout_ms);
}

int http_request_raw(const char *addr, const char *req, struct http_answer *a,
                     int timeout_ms)
{
    return http_exchange(addr, req, strlen(req), a, timeout_ms);
}

int http_stream_open(struct http_stream *s, const char *addr, const char *path,
                     int timeout_ms)
{
    return http_stream_open_with(s, addr, path, NULL, timeout_ms);
}

int http_stream_open_with(struct http_stream *s, const char *addr,
                          const char *path, const char *headers,
                          int timeout_ms)
{
    char req[1024];
    double deadline = emu_now_ms() + timeout_ms;
    char *he;
    int n;

    memset(s, 0, sizeof *s);
    s->fd = -1;
    n = snprintf(req, sizeof req,
                 "GET %s HTTP/1.1\r\nHost: %s\r\nAccept: text/event-stream\r\n"
                 "%s\r\n",
                 path, addr, headers ? headers : "");
    s->fd = http_open(addr);
    if (s->fd < 0)
        return -1;
    if (send_all(s->fd, req, (size_t)n) < 0)
        goto fail;
    while (!(he = head_end(s->raw, s->raw_len))) {
        long r = read_some(s->fd, s->raw + s->raw_len,
                           sizeof s->raw - 1 - s->raw_len, deadline);

        if (r <= 0)
            goto fail;
        s->raw_len += (size_t)r;
        s->raw[s->raw_len] = '\0';
    }
    /* The head as a string ends with the last header line's \r\n. */
    *(he - 2) = '\0';
    if (sscanf(s->raw, "HTTP/1.%*d %d", &s->status) != 1)
        goto fail;
    s->chunked = is_chunked(s->raw);
    if (!find_header(s->raw, "Content-Type", s->type, sizeof s->type))
        s->type[0] = '\0';
    memmove(s->raw, he, s->raw_len - (size_t)(he - s->raw));
    s->raw_len -= (size_t)(he - s->raw);
    return 0;

fail:
    fprintf(stderr, "http: GET %s: no answer\n", path);
    http_stream_close(s);
    return -1;
}

/* Copy the value of field in the event ev ("name: value" lines) into buf;
 * several "data:" lines are joined with newlines, as a browser does. */
static void event_field(const char *ev, size_t len, const char *field,
                        char *buf, size_t cap)
{
    size_t flen = strlen(field), used = 0, i = 0;

    buf[0] = '\0';
    while (i < len) {
        const char *line = ev + i;
        const char *eol = memchr(line, '\n', len - i);
        size_t llen = eol ? (size_t)(eol - line) : len - i;

        if (llen > flen && memcmp(line, field, flen) == 0 &&
            line[flen] == ':') {
            const char *v = line + flen + 1;
            size_t vlen = llen - flen - 1;

            if (vlen && *v == ' ')
                v++, vlen--;
            if (used && used + 1 < cap)
                buf[used++] = '\n';
            if (vlen > cap - 1 - used)
                vlen = cap - 1 - used;
            memcpy(buf + used, v, vlen);
            used += vlen;
            buf[used] = '\0';
        }
        i += llen + 1;
    }
}

/* Move what raw holds into text: whole chunks, or all of it unchunked. */
static int stream_decode(struct http_stream *s)
{
    if (s->chunked)
        return dechunk(s->raw, &s->raw_len, s->text, &s->text_len,
                       sizeof s->text, &s->eof);
    if (s->text_len + s->raw_len >= sizeof s->text)
        return -1;
    memcpy(s->text + s->text_len, s->raw, s->raw_len);
    s->text_len += s->raw_len;
    s->raw_len = 0;
    return 0;
}

/* Wait up to timeout_ms for a whole event in s->text: 1 (its length, up
 * to the blank line that ends it, in *len), 0 none in time, -1 the stream
 * ended or failed. */
static int stream_next(struct http_stream *s, size_t *len, int timeout_ms)
{
    double deadline = emu_now_ms() + timeout_ms;

    for (;;) {
        char *end;
        long r;

        /* What came with the head, or with the last event, first. */
        if (stream_decode(s) < 0)
            return -1;
        end = memmem(s->text, s->text_len, "\n\n", 2);
        if (end) {
            *len = (size_t)(end - s->text);
            return 1;
        }
        if (s->eof)
            return -1;
        r = read_some(s->fd, s->raw + s->raw_len,
                      sizeof s->raw - 1 - s->raw_len, deadline);
        if (r == -1)
            return 0;
        if (r <= 0)
            s->eof = 1;
        else
            s->raw_len += (size_t)r;
    }
}

/* Drop the event of len bytes (and its blank line) that stream_next
 * found. */
static void stream_take(struct http_stream *s, size_t len)
{
    memmove(s->text, s->text + len + 2, s->text_len - len - 2);
    s->text_len -= len + 2;
}

int http_stream_event(struct http_stream *s, char *name, size_t name_cap,
                      char *data, size_t data_cap, int timeout_ms)
{
    char id[32];
    size_t len;
    int r = stream_next(s, &len, timeout_ms);

    if (r != 1)
        return r;
    event_field(s->text, len, "event", name, name_cap);
    event_field(s->text, len, "data", data, data_cap);
    /* An event without an id keeps the last one (as browsers do). */
    event_field(s->text, len, "id", id, sizeof id);
    if (id[0])
        memcpy(s->id, id, sizeof id);
    stream_take(s, len);
    return 1;
}

int http_stream_raw(struct http_stream *s, char *buf, size_t cap, size_t *len,
                    int timeout_ms)
{
    size_t n;
    int r = stream_next(s, &n, timeout_ms);

    if (r != 1)
        return r;
    if (n + 2 > cap) {
        fprintf(stderr, "http: an event of %zu bytes, more than %zu\n", n + 1,
                cap - 1);
        return -1;
    }
    /* Its lines, the last one's newline included. */
    memcpy(buf, s->text, n + 1);
    buf[n + 1] = '\0';
    *len = n + 1;
    stream_take(s, n);
    return 1;
}

void http_stream_close(struct http_stream *s)
{
    if (s->fd >= 0)
        close(s->fd);
    s->fd = -1;
}

int http_load(const char *addr, const char *path, int n, int timeout_ms)
{
    double deadline = emu_now_ms() + timeout_ms;
    struct pollfd *pfd = calloc((size_t)n, sizeof *pfd);
    char(*head)[16] = calloc((size_t)n, sizeof *head);
    size_t *got = calloc((size_t)n, sizeof *got);
    char req[512], buf[4096];
    int i, open = 0, ok = 0, len;

    if (!pfd || !head || !got)
        goto out;
    for (i = 0; i < n; i++)
        pfd[i].fd = -1;
    len = snprintf(req, sizeof req,
                   "GET %s HTTP/1.1\r\nHost: %s\r\nConnection: close\r\n\r\n",
                   path, addr);
    /* Every connection open and its request sent before any answer is
     * read: n requests in the server's hands at once. */
    for (i = 0; i < n; i++) {
        pfd[i].fd = http_open(addr);
        pfd[i].events = POLLIN;
        if (pfd[i].fd < 0 || send_all(pfd[i].fd, req, (size_t)len) < 0)
            goto out;
        open++;
    }
    while (open > 0 && emu_now_ms() < deadline) {
        int r = poll(pfd, (nfds_t)n, (int)(deadline - emu_now_ms()) + 1);

        if (r < 0 && errno != EINTR)
            break;
        for (i = 0; r > 0 && i < n; i++) {
            ssize_t k;

            if (pfd[i].fd < 0 || !pfd[i].revents)
                continue;
            k = read(pfd[i].fd, buf, sizeof buf);
            if (k > 0 && got[i] < sizeof head[i] - 1) {
                size_t take = sizeof head[i] - 1 - got[i];

                memcpy(head[i] + got[i], buf,
                       (size_t)k < take ? (size_t)k : take);
                got[i] += (size_t)k < take ? (size_t)k : take;
            }
            if (k > 0)
                continue;
            /* The answer is whole: the server closed. */
            if (strncmp(head[i], "HTTP/1.1 200 ", 13) == 0)
                ok++;
            close(pfd[i].fd);
            pfd[i].fd = -1;
            open--;
        }
    }
out:
    for (i = 0; pfd && i < n; i++)
        if (pfd[i].fd >= 0)
            close(pfd[i].fd);
    free(pfd);
    free(head);
    free(got);
    return ok;
}

/* ---- a JSON checker: is an answer one valid JSON value? ---- */

struct json_in {
    const unsigned char *p, *end;
    int depth;
};

static void json_ws(struct json_in *in)
{
    while (in->p < in->end && (*in->p == ' ' || *in->p == '\t' ||
                               *in->p == '\n' || *in->p == '\r'))
        in->p++;
}

/* One UTF-8 character of a string (its first byte at in->p, >= 0x80):
 * 0, or -1 for a byte sequence that is not UTF-8. */
static int json_utf8(struct json_in *in)
{
    const unsigned char *p = in->p;
    unsigned char lo = 0x80, hi = 0xbf;
    int n, i;

    if (*p >= 0xc2 && *p <= 0xdf)
        n = 1;
    else if (*p >= 0xe0 && *p <= 0xef)
        n = 2;
    else if (*p >= 0xf0 && *p <= 0xf4)
        n = 3;
    else
        return -1;
    /* No overlong forms, no surrogates, nothing past U+10FFFF. */
    if (*p == 0xe0)
        lo = 0xa0;
    else if (*p == 0xed)
        hi = 0x9f;
    else if (*p == 0xf0)
        lo = 0x90;
    else if (*p == 0xf4)
        hi = 0x8f;
    if (in->end - p <= n)
        return -1;
    for (i = 1; i <= n; i++) {
        if (p[i] < (i == 1 ? lo : 0x80) || p[i] > (i == 1 ? hi : 0xbf))
            return -1;
    }
    in->p += n + 1;
    return 0;
}

static int json_string(struct json_in *in)
{
    int i;

    in->p++; /* the quote */
    while (in->p < in->end && *in->p != '"') {
        if (*in->p < 0x20)
            return -1;
        if (*in->p >= 0x80) {
            if (json_utf8(in) < 0)
                return -1;
            continue;
        }
        if (*in->p++ != '\\')
            continue;
        if (in->p == in->end)
            return -1;
        if (*in->p == 'u') {
            for (i = 1; i <= 4; i++)
                if (in->p + i >= in->end || !isxdigit(in->p[i]))
                    return -1;
            in->p += 5;
        } else if (strchr("\"\\/bfnrt", *in->p) && *in->p) {
            in->p++;
        } else {
            return -1;
        }
    }
    if (in->p == in->end)
        return -1;
    in->p++;
    return 0;
}

static int json_value(struct json_in *in);

/* An object or an array (its opening bracket at in->p). */
static int json_members(struct json_in *in, int object)
{
    const unsigned char close = object ? '}' : ']';

    if (++in->depth > 64)
        return -1;
    in->p++;
    json_ws(in);
    if (in->p < in->end && *in->p == close) {
        in->p++;
        in->depth--;
        return 0;
    }
    for (;;) {
        json_ws(in);
        if (object) {
            if (in->p == in->end || *in->p != '"' || json_string(in) < 0)
                return -1;
            json_ws(in);
            if (in->p == in->end || *in->p++ != ':')
                return -1;
        }
        if (json_value(in) < 0)
            return -1;
        json_ws(in);
        if (in->p == in->end)
            return -1;
        if (*in->p == close) {
            in->p++;
            in->depth--;
            return 0;
        }
        if (*in->p++ != ',')
            return -1;
    }
}

static int json_value(struct json_in *in)
{
    static const char *const words[] = {"true", "false", "null"};
    size_t i, n;

    json_ws(in);
    if (in->p == in->end)
        return -1;
    if (*in->p == '{' || *in->p == '[')
        return json_members(in, *in->p == '{');
    if (*in->p == '"')
        return json_string(in);
    for (i = 0; i < sizeof words / sizeof words[0]; i++) {
        n = strlen(words[i]);
        if ((size_t)(in->end - in->p) >= n &&
            memcmp(in->p, words[i], n) == 0) {
            in->p += n;
            return 0;
        }
    }
    /* A number: -?int frac? exp? */
    if (*in->p == '-')
        in->p++;
    if (in->p == in->end || !isdigit(*in->p))
        return -1;
    if (*in->p == '0')
        in->p++;
    else
        while (in->p < in->end && isdigit(*in->p))
            in->p++;
    if (in->p < in->end && *in->p == '.') {
        if (++in->p == in->end || !isdigit(*in->p))
            return -1;
        while (in->p < in->end && isdigit(*in->p))
            in->p++;
    }
    if (in->p < in->end && (*in->p == 'e' || *in->p == 'E')) {
        in->p++;
        if (in->p < in->end && (*in->p == '+' || *in->p == '-'))
            in->p++;
        if (in->p == in->end || !isdigit(*in->p))
            return -1;
        while (in->p < in->end && isdigit(*in->p))
            in->p++;
    }
    return 0;
}

int http_json_valid(const char *text, size_t len)
{
    struct json_in in = {(const unsigned char *)text,
                         (const unsigned char *)text + len, 0};

    if (json_value(&in) < 0)
        return 0;
    json_ws(&in);
    return in.p == in.end;
}
