/*
 * The communication log: formats one line per packet from the device's
 * trace hooks (see log.h for the line format). Received packets arrive
 * parsed (a struct wsg_frame, or a checksum or size error with the ID);
 * sent packets arrive as raw bytes and are taken apart here. Parameters
 * are decoded by the schema's layout for the command (wsg/schema.h), so
 * every field the schema knows is shown by name. Each line is built in a
 * stack buffer and handed to stdio in one call, so a line is never split
 * between two flushes, nor between two files when the size bound
 * (--log-max) moves the file aside.
 */
#define _GNU_SOURCE /* localtime_r, clock_gettime */

#include "log.h"

#include <errno.h>
#include <stdarg.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "wsg/proto.h"

/* Raw payload bytes shown at most; a 256-byte Loop would make an
 * unreadable line. */
#define WSG_LOG_HEX_MAX 32u

struct line {
    char s[1024];
    size_t n;
};

static void add(struct line *l, const char *fmt, ...)
    __attribute__((format(printf, 2, 3)));

static void add(struct line *l, const char *fmt, ...)
{
    va_list ap;
    int r;

    if (l->n >= sizeof l->s)
        return;
    va_start(ap, fmt);
    r = vsnprintf(l->s + l->n, sizeof l->s - l->n, fmt, ap);
    va_end(ap);
    if (r > 0)
        l->n += (size_t)r < sizeof l->s - l->n ? (size_t)r
                                               : sizeof l->s - l->n - 1;
}

/* What every line has (its head, hex bytes) is appended by hand: printf's
 * machinery per field made the log cost a fifth of the emulator's
 * throughput at full load. */
static void put(struct line *l, const char *p, size_t n)
{
    size_t room = sizeof l->s - 1 - l->n;

    if (l->n >= sizeof l->s - 1)
        return;
    if (n > room)
        n = room;
    memcpy(l->s + l->n, p, n);
    l->n += n;
}

static void put_str(struct line *l, const char *p)
{
    put(l, p, strlen(p));
}

/* v in decimal, at least width digits. */
static void put_uint(struct line *l, unsigned long long v, int width)
{
    char b[24];
    int i = sizeof b;

    do {
        b[--i] = (char)('0' + v % 10);
        v /= 10;
    } while (v || (int)sizeof b - i < width);
    put(l, b + i, sizeof b - (size_t)i);
}

static void put_hex2(struct line *l, uint8_t v)
{
    static const char digit[] = "0123456789ABCDEF";
    char b[2];

    b[0] = digit[v >> 4];
    b[1] = digit[v & 15];
    put(l, b, 2);
}

/* Values as the log writes them: "width=110.000", "flags=0x03(relative|
 * stop-on-block)", "grasp-state=4(HOLDING)", "tag=\"lab-2\"". */
static const struct wsg_value_style log_style = {3,   "(", "|",
                                                 ")", 0,   WSG_LOG_HEX_MAX};

/* " name=value" of one field. */
static void add_value(struct line *l, const struct wsg_value *v)
{
    put(l, " ", 1);
    put_str(l, v->field->name);
    put(l, "=", 1);
    if (l->n < sizeof l->s - 1)
        l->n +=
            wsg_value_format(v, &log_style, l->s + l->n, sizeof l->s - l->n);
}

/* The fields of a payload by the schema's layout for it. One that does
 * not fit (a length the dispatcher refuses, an unknown ID) is shown as
 * hex: the log shows what was sent, not what was meant. */
static void add_fields(struct line *l, const struct wsg_layout *layout,
                       const uint8_t *p, size_t n)
{
    static const struct wsg_field raw = WSG_F_BYTES("data", WSG_FRAME_MAX);
    struct wsg_value v[WSG_FIELDS_MAX];
    int k = wsg_layout_decode(layout, p, n, v), i;

    if (k < 0) {
        memset(v, 0, sizeof v[0]);
        v[0].field = &raw;
        v[0].data = p;
        v[0].len = n;
        k = n ? 1 : 0;
    }
    for (i = 0; i < k; i++)
        add_value(l, &v[i]);
}

/* Bytes as the schema's raw field shows them ("data=01 02 ..."). */
static void add_raw(struct line *l, const uint8_t *p, size_t n)
{
    static const struct wsg_field raw = WSG_F_BYTES("data", WSG_FRAME_MAX);
    struct wsg_value v;

    if (n == 0)
        return;
    memset(&v, 0, sizeof v);
    v.field = &raw;
    v.data = p;
    v.len = n;
    add_value(l, &v);
}

static void decode_in(struct line *l, uint8_t id, const uint8_t *p, size_t n)
{
    add_fields(l, &wsg_schema[id].request, p, n);
}

/* Parameters of a reply, after its status. */
static void decode_out(struct line *l, uint8_t id, const uint8_t *p, size_t n)
{
    if (n == 0)
        return; /* a status only: most errors, and every final result */
    add_fields(l, &wsg_schema[id].reply, p, n);
    /* The firmware is the one emulated; which emulator answered is worth
     * a line in a bug report too. */
    if (id == WSG_CMD_GET_SYSTEM_INFO &&
        wsg_layout_fits(&wsg_schema[id].reply, n))
        add(l, " emulator=wsgemu-%s", WSG_VERSION);
}

/* Wall clock and simulated time. */
static void head_time(struct wsg_log_tap *tap, struct line *l)
{
    struct wsg_log *lg = tap->log;
    struct timespec ts;
    uint64_t t = wsg_axis_time(wsg_device_axis_const(tap->dev));

    clock_gettime(CLOCK_REALTIME, &ts);
    if (ts.tv_sec != lg->sec || lg->clock[0] == '\0') {
        struct tm tm;

        lg->sec = ts.tv_sec;
        if (localtime_r(&ts.tv_sec, &tm))
            strftime(lg->clock, sizeof lg->clock, "%H:%M:%S", &tm);
    }
    put_str(l, lg->clock);
    put(l, ".", 1);
    put_uint(l, (unsigned long long)(ts.tv_nsec / 1000000L), 3);
    put(l, " t=", 3);
    put_uint(l, (unsigned long long)(t / 1000000u), 1);
    put(l, ".", 1);
    put_uint(l, (unsigned long long)(t % 1000000u), 6);
    put(l, " ", 1);
    if (tap->index >= 0) {
        put(l, "#", 1);
        put_uint(l, (unsigned long long)tap->index, 1);
        put(l, " ", 1);
    }
}

/* Wall clock, simulated time, peer, direction, ID and name. */
static void head(struct wsg_log_tap *tap, struct line *l,
                 const struct wsg_session *s, const char *dir, uint8_t id)
{
    const char *name = wsg_cmd_name(id);

    head_time(tap, l);
    put_str(l, s->peer[0] ? s->peer : "?");
    put(l, " ", 1);
    put_str(l, dir);
    put(l, " ", 1);
    put_hex2(l, id);
    put(l, "h ", 2);
    put_str(l, name ? name : "unknown");
}

static int open_file(struct wsg_log *l, const char *path, const char *mode,
                     char *err, size_t errcap);

/* The file reached its bound: it becomes PATH.old and a new one begins at
 * PATH. When the file at PATH is no longer this one (logrotate moved it
 * and its SIGHUP has not come yet), a new one begins without moving
 * anything. When neither can be done (the directory is read-only to the
 * daemon), the file is cut to nothing: the bound holds whatever
 * happens. */
static void rotate(struct wsg_log *lg)
{
    size_t n = strlen(lg->path) + 5;
    struct wsg_log fresh;
    struct stat now, mine;
    char err[256], *old;
    int moved = 0;

    fflush(lg->f);
    old = malloc(n);
    if (old && fstat(fileno(lg->f), &mine) == 0) {
        snprintf(old, n, "%s.old", lg->path);
        if (stat(lg->path, &now) < 0 || now.st_dev != mine.st_dev ||
            now.st_ino != mine.st_ino)
            moved = 1;
        else
            moved = rename(lg->path, old) == 0;
    }
    free(old);
    memset(&fresh, 0, sizeof fresh);
    if (moved && open_file(&fresh, lg->path, "w", err, sizeof err) == 0) {
        fclose(lg->f);
        free(lg->buf);
        lg->f = fresh.f;
        lg->buf = fresh.buf;
    } else if (ftruncate(fileno(lg->f), 0) < 0 ||
               fseek(lg->f, 0, SEEK_SET) < 0) {
        return; /* nothing to be done: size stays, the next line tries */
    }
    lg->size = 0;
}

static void emit(struct wsg_log *lg, struct line *l)
{
    if (l->n >= sizeof l->s - 1)
        l->n = sizeof l->s - 2; /* a cut line still ends its line */
    l->s[l->n++] = '\n';
    if (lg->f && lg->own && lg->max && lg->size > 0 &&
        lg->size + l->n > lg->max)
        rotate(lg);
    if (lg->f) {
        fwrite(l->s, 1, l->n, lg->f);
        lg->size += l->n;
    }
    if (lg->sink)
        lg->sink(lg->sink_ctx, l->s, l->n);
}

/* Is anyone reading lines? Taps stay attached while no one is (the web
 * page's view comes and goes); a line is then not even made. */
static int wanted(const struct wsg_log *lg)
{
    return lg->f || lg->sink;
}

static void log_in(void *ctx, const struct wsg_session *s,
                   const struct wsg_frame *f, enum wsg_parse_event ev)
{
    struct wsg_log_tap *tap = ctx;
    struct line l;

    if (!wanted(tap->log))
        return;
    l.n = 0;
    head(tap, &l, s, "in", f->id);
    if (ev == WSG_PARSE_BAD_CRC)
        add(&l, " checksum-error");
    else if (ev == WSG_PARSE_OVERSIZE)
        add(&l, " oversize");
    else if (wsg_device_registered(tap->dev, f->id))
        add_raw(&l, f->payload, f->len); /* a script's own command */
    else
        decode_in(&l, f->id, f->payload, f->len);
    emit(tap->log, &l);
}

/* A text session's line (GCL): "PEER in MOVE(30,100)", "PEER out FIN
 * MOVE", without its newline. */
static void log_text(struct wsg_log_tap *tap, const struct wsg_session *s,
                     const char *dir, const char *text, size_t len)
{
    struct line l;

    while (len > 0 && (text[len - 1] == '\n' || text[len - 1] == '\r'))
        len--;
    l.n = 0;
    head_time(tap, &l);
    put_str(&l, s->peer[0] ? s->peer : "?");
    put(&l, " ", 1);
    put_str(&l, dir);
    put(&l, " ", 1);
    put(&l, text, len);
    emit(tap->log, &l);
}

static void log_line(void *ctx, const struct wsg_session *s, const char *line,
                     size_t len)
{
    log_text(ctx, s, "in", line, len);
}

static void log_out(void *ctx, const struct wsg_session *s, const uint8_t *pkt,
                    size_t len)
{
    struct wsg_log_tap *tap = ctx;
    struct line l;
    size_t n;

    if (!wanted(tap->log))
        return;
    if (s->flags & WSG_SESSION_TEXT) {
        log_text(tap, s, "out", (const char *)pkt, len);
        return;
    }

    /* The device sends whole packets; the checks keep a malformed one
     * from being read past its end. */
    if (len < WSG_HEADER_LEN + WSG_CRC_LEN)
        return;
    n = wsg_get_u16(pkt + 4);
    if (WSG_HEADER_LEN + n + WSG_CRC_LEN > len)
        return;
    l.n = 0;
    /* A script's answer is its own bytes: no status of the firmware's. */
    if (wsg_device_registered(tap->dev, pkt[3]) || n < 2) {
        head(tap, &l, s, "out", pkt[3]);
        add_raw(&l, pkt + WSG_HEADER_LEN, n);
        emit(tap->log, &l);
        return;
    }
    head(tap, &l, s, "out", pkt[3]);
    put(&l, " ", 1);
    put_str(&l, wsg_status_name(wsg_get_u16(pkt + WSG_HEADER_LEN)));
    decode_out(&l, pkt[3], pkt + WSG_HEADER_LEN + 2, n - 2);
    emit(tap->log, &l);
}

/* "HH:MM:SS.mmm t=SIM WHO event TEXT". */
static void event_line(struct wsg_log_tap *tap, const char *who,
                       const char *text)
{
    struct line l;

    l.n = 0;
    head_time(tap, &l);
    put_str(&l, who);
    put(&l, " event ", 7);
    put_str(&l, text);
    emit(tap->log, &l);
}

static void log_event(void *ctx, const char *who, const char *text)
{
    struct wsg_log_tap *tap = ctx;

    if (wanted(tap->log))
        event_line(tap, who, text);
}

/* A file of the log: appended to when mode is "a". */
static int open_file(struct wsg_log *l, const char *path, const char *mode,
                     char *err, size_t errcap)
{
    FILE *f = fopen(path, mode);
    struct stat st;
    char *buf;
    int r;

    if (!f) {
        r = -errno;
        snprintf(err, errcap, "--log: cannot open '%s': %s", path,
                 strerror(-r));
        return r;
    }
    /* What it holds already counts against the bound. */
    l->size = fstat(fileno(f), &st) == 0 ? (uint64_t)st.st_size : 0;
    /* Fully buffered; the loop flushes after each batch of events. */
    buf = malloc(WSG_LOG_BUFSIZE);
    if (buf)
        setvbuf(f, buf, _IOFBF, WSG_LOG_BUFSIZE);
    l->f = f;
    l->own = 1;
    l->buf = buf;
    return 0;
}

int wsg_log_open(struct wsg_log *l, const char *path, char *err, size_t errcap)
{
    memset(l, 0, sizeof *l);
    if (strcmp(path, "-") == 0) {
        /* A terminal watcher wants each line as it happens; stderr is
         * unbuffered by default, line buffering keeps lines whole. */
        l->f = stderr;
        setvbuf(stderr, NULL, _IOLBF, 0);
        return 0;
    }
    l->path = path;
    return open_file(l, path, "w", err, errcap);
}

void wsg_log_limit(struct wsg_log *l, uint64_t max)
{
    l->max = max;
}

int wsg_log_reopen(struct wsg_log *l, const char *path, char *err,
                   size_t errcap)
{
    struct wsg_log fresh;
    int r;

    if (!l->own)
        return 0; /* stderr, or closed: nothing was renamed away */
    memset(&fresh, 0, sizeof fresh);
    /* The new file first: if it cannot be opened, lines go on into the
     * old one rather than nowhere. */
    r = open_file(&fresh, path, "a", err, errcap);
    if (r < 0)
        return r;
    fflush(l->f);
    fclose(l->f);
    free(l->buf);
    l->f = fresh.f;
    l->buf = fresh.buf;
    l->size = fresh.size;
    l->path = path;
    return 0;
}

void wsg_log_attach(struct wsg_log *l, struct wsg_log_tap *tap,
                    struct wsg_device *d, int index)
{
    tap->log = l;
    tap->dev = d;
    tap->index = index;
    d->trace_in = log_in;
    d->trace_out = log_out;
    d->trace_line = log_line;
    d->trace_event = log_event;
    d->trace_ctx = tap;
}

void wsg_log_detach(struct wsg_log_tap *tap, struct wsg_device *d)
{
    if (d->trace_ctx != tap)
        return;
    d->trace_in = NULL;
    d->trace_out = NULL;
    d->trace_line = NULL;
    d->trace_event = NULL;
    d->trace_ctx = NULL;
}

void wsg_log_text(struct wsg_log_tap *tap, const char *who, const char *text,
                  size_t len)
{
    struct line l;

    if (!tap->log || !wanted(tap->log))
        return;
    while (len > 0) {
        const char *nl = memchr(text, '\n', len);
        size_t n = nl ? (size_t)(nl - text) : len;

        l.n = 0;
        head_time(tap, &l);
        put_str(&l, who);
        put(&l, " print ", 7);
        put(&l, text, n);
        emit(tap->log, &l);
        n += nl ? 1 : 0;
        text += n;
        len -= n;
    }
}

void wsg_log_event(struct wsg_log_tap *tap, const char *who, const char *text)
{
    if (tap->log && wanted(tap->log))
        event_line(tap, who, text);
}

void wsg_log_sink(struct wsg_log *l,
                  void (*fn)(void *ctx, const char *line, size_t len),
                  void *ctx)
{
    l->sink = fn;
    l->sink_ctx = ctx;
}

void wsg_log_flush(struct wsg_log *l)
{
    if (l->f)
        fflush(l->f);
}

void wsg_log_close(struct wsg_log *l)
{
    if (!l->f)
        return;
    fflush(l->f);
    if (l->own)
        fclose(l->f);
    l->f = NULL;
    free(l->buf);
    l->buf = NULL;
}
