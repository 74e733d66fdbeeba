/*
 * The communication log: formats one line per packet from the device's
 * trace hooks (see log.h for the line format). Received packets arrive
 * parsed (a struct wsg_frame, or a checksum or size error with the ID);
 * sent packets arrive as raw bytes and are taken apart here. Each line is
 * built in a stack buffer and handed to stdio in one call, so a line is
 * never split between two flushes.
 */
#define _GNU_SOURCE /* localtime_r, clock_gettime */

#include "log.h"

#include <errno.h>
#include <stdarg.h>
#include <stdlib.h>
#include <string.h>

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

static void add_hex(struct line *l, const uint8_t *p, size_t n)
{
    size_t i;

    put_str(l, " data=");
    for (i = 0; i < n && i < WSG_LOG_HEX_MAX; i++) {
        if (i)
            put(l, " ", 1);
        put_hex2(l, p[i]);
    }
    if (n > WSG_LOG_HEX_MAX)
        add(l, " ...(%zu bytes)", n);
}

static void add_text(struct line *l, const char *name, const uint8_t *p,
                     size_t n)
{
    size_t i;

    add(l, " %s=\"", name);
    for (i = 0; i < n; i++)
        add(l, p[i] >= 0x20 && p[i] < 0x7F && p[i] != '"' ? "%c" : "\\x%02X",
            p[i]);
    add(l, "\"");
}

static void add_f32(struct line *l, const char *name, const uint8_t *p)
{
    add(l, " %s=%.3f", name, (double)wsg_get_f32(p));
}

static void add_flags(struct line *l, uint32_t flags)
{
    static const struct {
        uint32_t bit;
        const char *name;
    } names[] = {{WSG_SF_REFERENCED, "REFERENCED"},
                 {WSG_SF_MOVING, "MOVING"},
                 {WSG_SF_BLOCKED_MINUS, "BLOCKED_MINUS"},
                 {WSG_SF_BLOCKED_PLUS, "BLOCKED_PLUS"},
                 {WSG_SF_SOFT_LIMIT_MINUS, "SOFT_LIMIT_MINUS"},
                 {WSG_SF_SOFT_LIMIT_PLUS, "SOFT_LIMIT_PLUS"},
                 {WSG_SF_AXIS_STOPPED, "AXIS_STOPPED"},
                 {WSG_SF_TARGET_POS_REACHED, "TARGET_POS_REACHED"},
                 {WSG_SF_OVERDRIVE_MODE, "OVERDRIVE_MODE"},
                 {WSG_SF_FORCECNTL_MODE, "FORCECNTL_MODE"},
                 {WSG_SF_FAST_STOP, "FAST_STOP"},
                 {WSG_SF_TEMP_WARNING, "TEMP_WARNING"},
                 {WSG_SF_TEMP_FAULT, "TEMP_FAULT"},
                 {WSG_SF_POWER_FAULT, "POWER_FAULT"},
                 {WSG_SF_CURR_FAULT, "CURR_FAULT"},
                 {WSG_SF_FINGER_FAULT, "FINGER_FAULT"},
                 {WSG_SF_CMD_FAILURE, "CMD_FAILURE"},
                 {WSG_SF_SCRIPT_RUNNING, "SCRIPT_RUNNING"},
                 {WSG_SF_SCRIPT_FAILURE, "SCRIPT_FAILURE"}};
    size_t i;
    int first = 1;

    add(l, " flags=0x%08lX", (unsigned long)flags);
    for (i = 0; i < sizeof names / sizeof names[0]; i++) {
        if (flags & names[i].bit) {
            add(l, "%s%s", first ? " (" : "|", names[i].name);
            first = 0;
        }
    }
    if (!first)
        add(l, ")");
}

static const char *grasp_state_name(unsigned s)
{
    static const char *const names[] = {"IDLE",        "GRASPING", "NO_PART",
                                        "PART_LOST",   "HOLDING",  "RELEASING",
                                        "POSITIONING", "ERROR"};

    return s < sizeof names / sizeof names[0] ? names[s] : "?";
}

/* Parameters of a request, by command. Lengths the dispatcher would refuse
 * fall back to hex: the log shows what was sent, not what was meant. */
static void decode_in(struct line *l, uint8_t id, const uint8_t *p, size_t n)
{
    switch (id) {
    case WSG_CMD_HOMING:
        if (n != 1)
            break;
        add(l, " direction=%s",
            p[0] == 0   ? "default"
            : p[0] == 1 ? "positive"
            : p[0] == 2 ? "negative"
                        : "invalid");
        return;
    case WSG_CMD_PREPOSITION:
        if (n != 9)
            break;
        add(l, " flags=0x%02X", p[0]);
        if (p[0] & WSG_MOVE_RELATIVE)
            add(l, "(relative)");
        add_f32(l, "width", p + 1);
        add_f32(l, "speed", p + 5);
        if (p[0] & WSG_MOVE_STOP_ON_BLOCK)
            add(l, " stop-on-block");
        return;
    case WSG_CMD_GRASP:
    case WSG_CMD_RELEASE:
        if (n != 8)
            break;
        add_f32(l, "width", p);
        add_f32(l, "speed", p + 4);
        return;
    case WSG_CMD_SET_ACCELERATION:
        if (n != 4)
            break;
        add_f32(l, "acceleration", p);
        return;
    case WSG_CMD_SET_FORCE_LIMIT:
        if (n != 4)
            break;
        add_f32(l, "force", p);
        return;
    case WSG_CMD_SET_SOFT_LIMITS:
        if (n != 8)
            break;
        add_f32(l, "minus", p);
        add_f32(l, "plus", p + 4);
        return;
    case WSG_CMD_OVERDRIVE:
        if (n != 1)
            break;
        add(l, " overdrive=%s", p[0] ? "on" : "off");
        return;
    case WSG_CMD_GET_SYSTEM_STATE:
    case WSG_CMD_GET_GRASP_STATE:
    case WSG_CMD_GET_WIDTH:
    case WSG_CMD_GET_SPEED:
    case WSG_CMD_GET_FORCE:
        if (n != 3)
            break;
        add(l, " auto-update=%s%s period=%ums", p[0] & 1 ? "on" : "off",
            p[0] & 2 ? " change-only" : "", (unsigned)wsg_get_u16(p + 1));
        return;
    case WSG_CMD_SET_DEVICE_TAG:
        add_text(l, "tag", p, n);
        return;
    default:
        break;
    }
    if (n)
        add_hex(l, p, n);
}

/* Parameters of a reply (after its status), by command. */
static void decode_out(struct line *l, uint8_t id, const uint8_t *p, size_t n)
{
    if (n == 0)
        return; /* a status only: most errors, and every final result */
    switch (id) {
    case WSG_CMD_GET_ACCELERATION:
        if (n != 4)
            break;
        add_f32(l, "acceleration", p);
        return;
    case WSG_CMD_GET_FORCE_LIMIT:
        if (n != 4)
            break;
        add_f32(l, "force", p);
        return;
    case WSG_CMD_GET_SOFT_LIMITS:
        if (n != 8)
            break;
        add_f32(l, "minus", p);
        add_f32(l, "plus", p + 4);
        return;
    case WSG_CMD_GET_SYSTEM_STATE:
        if (n != 4)
            break;
        add_flags(l, wsg_get_u32(p));
        return;
    case WSG_CMD_GET_GRASP_STATE:
        if (n != 1)
            break;
        add(l, " state=%u(%s)", p[0], grasp_state_name(p[0]));
        return;
    case WSG_CMD_GET_GRASP_STATS:
        if (n != 8)
            break;
        add(l, " total=%lu no-part=%u lost-part=%u",
            (unsigned long)wsg_get_u32(p), (unsigned)wsg_get_u16(p + 4),
            (unsigned)wsg_get_u16(p + 6));
        return;
    case WSG_CMD_GET_WIDTH:
        if (n != 4)
            break;
        add_f32(l, "width", p);
        return;
    case WSG_CMD_GET_SPEED:
        if (n != 4)
            break;
        add_f32(l, "speed", p);
        return;
    case WSG_CMD_GET_FORCE:
        if (n != 4)
            break;
        add_f32(l, "force", p);
        return;
    case WSG_CMD_GET_TEMPERATURE:
        if (n != 2)
            break;
        add(l, " temperature=%.1f", (int16_t)wsg_get_u16(p) / 10.0);
        return;
    case WSG_CMD_GET_SYSTEM_INFO: {
        unsigned sw;

        if (n != 8)
            break;
        sw = wsg_get_u16(p + 2);
        /* The firmware is the one emulated; which emulator answered is
         * worth a line in a bug report too. */
        add(l,
            " type=%u hwrev=%u swrev=%u.%u.%u serial=%lu emulator=wsgemu-%s",
            p[0], p[1], sw >> 12, (sw >> 8) & 0xFu, (sw >> 4) & 0xFu,
            (unsigned long)wsg_get_u32(p + 4), WSG_VERSION);
        return;
    }
    case WSG_CMD_GET_DEVICE_TAG:
        add_text(l, "tag", p, n);
        return;
    case WSG_CMD_GET_SYSTEM_LIMITS:
        if (n != 32)
            break;
        add_f32(l, "stroke", p);
        add_f32(l, "min-speed", p + 4);
        add_f32(l, "max-speed", p + 8);
        add_f32(l, "min-acc", p + 12);
        add_f32(l, "max-acc", p + 16);
        add_f32(l, "min-force", p + 20);
        add_f32(l, "nom-force", p + 24);
        add_f32(l, "ovr-force", p + 28);
        return;
    default:
        break;
    }
    if (n)
        add_hex(l, p, n);
}

/* Wall clock, simulated time, peer, direction, ID and name. */
static void head(struct wsg_log_tap *tap, struct line *l,
                 const struct wsg_session *s, const char *dir, uint8_t id)
{
    struct wsg_log *lg = tap->log;
    struct timespec ts;
    const char *name = wsg_cmd_name(id);
    uint64_t t = tap->dev->axis.time_us;

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
    put_str(l, s->peer[0] ? s->peer : "?");
    put(l, " ", 1);
    put_str(l, dir);
    put(l, " ", 1);
    put_hex2(l, id);
    put(l, "h ", 2);
    put_str(l, name ? name : "unknown");
}

static void emit(struct wsg_log *lg, struct line *l)
{
    if (l->n >= sizeof l->s - 1)
        l->n = sizeof l->s - 2; /* a cut line still ends its line */
    l->s[l->n++] = '\n';
    fwrite(l->s, 1, l->n, lg->f);
}

static void log_in(void *ctx, const struct wsg_session *s,
                   const struct wsg_frame *f, enum wsg_parse_event ev)
{
    struct wsg_log_tap *tap = ctx;
    struct line l;

    l.n = 0;
    head(tap, &l, s, "in", f->id);
    if (ev == WSG_PARSE_BAD_CRC)
        add(&l, " checksum-error");
    else if (ev == WSG_PARSE_OVERSIZE)
        add(&l, " oversize");
    else
        decode_in(&l, f->id, f->payload, f->len);
    emit(tap->log, &l);
}

static void log_out(void *ctx, const struct wsg_session *s, const uint8_t *pkt,
                    size_t len)
{
    struct wsg_log_tap *tap = ctx;
    struct line l;
    size_t n;

    /* The device only sends whole replies of its own making; the checks
     * keep a malformed one from being read past its end. */
    if (len < WSG_HEADER_LEN + 2 + WSG_CRC_LEN)
        return;
    n = wsg_get_u16(pkt + 4);
    if (n < 2 || WSG_HEADER_LEN + n + WSG_CRC_LEN > len)
        return;
    l.n = 0;
    head(tap, &l, s, "out", pkt[3]);
    put(&l, " ", 1);
    put_str(&l, wsg_status_name(wsg_get_u16(pkt + WSG_HEADER_LEN)));
    decode_out(&l, pkt[3], pkt + WSG_HEADER_LEN + 2, n - 2);
    emit(tap->log, &l);
}

int wsg_log_open(struct wsg_log *l, const char *path, char *err, size_t errcap)
{
    int r;

    memset(l, 0, sizeof *l);
    if (strcmp(path, "-") == 0) {
        /* A terminal watcher wants each line as it happens; stderr is
         * unbuffered by default, line buffering keeps lines whole. */
        l->f = stderr;
        setvbuf(stderr, NULL, _IOLBF, 0);
    } else {
        l->f = fopen(path, "w");
        if (!l->f) {
            r = -errno;
            snprintf(err, errcap, "--log: cannot open '%s': %s", path,
                     strerror(errno));
            return r;
        }
        l->own = 1;
        /* Fully buffered; the loop flushes after each batch of events. */
        l->buf = malloc(WSG_LOG_BUFSIZE);
        if (l->buf)
            setvbuf(l->f, l->buf, _IOFBF, WSG_LOG_BUFSIZE);
    }
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
    d->trace_ctx = tap;
}

void wsg_log_detach(struct wsg_log_tap *tap, struct wsg_device *d)
{
    if (d->trace_ctx != tap)
        return;
    d->trace_in = NULL;
    d->trace_out = NULL;
    d->trace_ctx = NULL;
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
