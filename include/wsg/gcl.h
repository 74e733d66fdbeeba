/*
 * GCL, the text command interface of later WSG firmware ("Use text based
 * interface" on the web page): one command per line on the TCP port,
 * answered by lines. Two layers, as for the binary protocol:
 *
 *   - the line codec (gcl/line.c): bytes in, whole lines or the reason a
 *     line is refused (too long, binary bytes) out, and a line parsed into
 *     a command (NAME(args), NAME?, NAME[i]?, NAME=value). No I/O, no
 *     clock, no allocation; the state is the caller's.
 *   - the interpreter (gcl/gcl.c): a connection's GCL side. Most commands
 *     become the binary command they stand for and go through the device's
 *     dispatcher, so that every check and error code is the command
 *     table's; the binary answers come back through the session's format
 *     hook and leave as text: "ACK MOVE" at once, "FIN MOVE" or
 *     "ERR MOVE 19" when the motion ends, "POS=54.2" for a query,
 *     "@POS=54.2" for an AUTOSEND stream. Each line leaves in its own
 *     write (wsg_device_send, through the output hook like any packet).
 */
#ifndef WSG_GCL_H
#define WSG_GCL_H

#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

#include "wsg/device.h"

/* Longest line, without its newline; a longer one is answered ERR and
 * skipped up to its newline. */
#define WSG_GCL_LINE_MAX 256u
#define WSG_GCL_NAME_MAX 15u
#define WSG_GCL_ARGS_MAX 4u
#define WSG_GCL_STR_MAX  15u

/* ---- the line codec ---- */

struct wsg_gcl_line {
    uint16_t len;
    uint8_t overlong; /* past WSG_GCL_LINE_MAX: skipping to the newline */
    uint8_t binary;   /* a byte no text line has */
    char buf[WSG_GCL_LINE_MAX + 2]; /* the line, a CR, the NUL */
};

enum wsg_gcl_event {
    WSG_GCL_NONE = 0, /* all input consumed, no line ended */
    WSG_GCL_LINE,     /* a line (without CR LF), NUL-terminated */
    WSG_GCL_TOO_LONG, /* a line longer than WSG_GCL_LINE_MAX ended */
    WSG_GCL_BINARY    /* a line with bytes that are not text ended */
};

void wsg_gcl_line_init(struct wsg_gcl_line *l);
/* Consume bytes up to and including the next newline. Returns the bytes
 * consumed; *ev tells what ended there, *line and *n the line for
 * WSG_GCL_LINE (valid until the next call). An empty line is no event. */
/* One answer line from a format into buf (cap bytes, at least 2): the
 * text, cut to fit, and its newline. Returns its length with the
 * newline, 0 on a format error. The GCL interpreter's lines and the
 * control channel's answers are made so. No NUL is written after it. */
size_t wsg_gcl_line_vformat(char *buf, size_t cap, const char *fmt,
                            va_list ap);
size_t wsg_gcl_line_feed(struct wsg_gcl_line *l, const uint8_t *data,
                         size_t len, enum wsg_gcl_event *ev, const char **line,
                         size_t *n);

enum wsg_gcl_form {
    WSG_GCL_CALL,  /* NAME(args) */
    WSG_GCL_QUERY, /* NAME? or NAME[i]? */
    WSG_GCL_SET    /* NAME=value */
};

struct wsg_gcl_arg {
    int is_str;
    double num;                    /* a number; true 1, false 0 */
    char str[WSG_GCL_STR_MAX + 1]; /* a "quoted" string */
};

struct wsg_gcl_cmd {
    char name[WSG_GCL_NAME_MAX + 1]; /* upper case */
    enum wsg_gcl_form form;
    int index; /* NAME[i]?; -1: none */
    unsigned nargs;
    struct wsg_gcl_arg arg[WSG_GCL_ARGS_MAX]; /* SET: arg[0] */
};

/* Parse one line. Returns 0, or -1 when it is no command; the name (upper
 * case) is in c->name as far as it could be read either way ("" when not
 * even that). */
int wsg_gcl_parse(const char *line, size_t n, struct wsg_gcl_cmd *c);

/* ---- the interpreter ---- */

struct wsg_gcl_config {
    double release_pullback; /* mm: RELEASE() opens this far */
    double default_speed;    /* mm/s: MOVE, GRIP, RELEASE without a speed */
};

struct wsg_gcl_command; /* a row of gcl.c's command table */

/* A connection's GCL side. */
struct wsg_gcl {
    struct wsg_device *dev;
    struct wsg_session *s;
    struct wsg_gcl_config cfg;
    struct wsg_gcl_line line;
    int verbose;
    double pwt, clt; /* this connection's overrides; < 0: the gripper's */
    /* The command running (between its dispatch and its answer): its
     * name, the binary ID it became and how its answer is written. */
    const struct wsg_gcl_command *cur;
    uint8_t cur_id;
    int answered;
};

/* Set up g for session s of d: s's format hook now writes text. */
void wsg_gcl_init(struct wsg_gcl *g, struct wsg_device *d,
                  struct wsg_session *s, const struct wsg_gcl_config *cfg);
/* Bytes the client sent: every complete line is run and answered. */
void wsg_gcl_input(struct wsg_gcl *g, const uint8_t *data, size_t len);

#endif
