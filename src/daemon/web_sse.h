/*
 * The web page's event stream (GET /events, Server-Sent Events) packs the
 * communication log into "log" events here: a pure function of a buffer,
 * the log's ring and a reader's offset, apart from the server so that its
 * unit test and its fuzz harness call it as the server does. The log's
 * text is anyone's (a packet's payload, a GCL line, a script's print), so
 * the packing is bounded by the buffer whatever the lines and the sizes
 * are, and what it writes is well-formed SSE whatever the text holds.
 */
#ifndef WSG_DAEMON_WEB_SSE_H
#define WSG_DAEMON_WEB_SSE_H

#include <stddef.h>
#include <stdint.h>

/* "event: log\n", the first line of every log event. */
#define WSG_WEB_SSE_HEAD_LEN 11u
/* "data: " and the newline around each line. */
#define WSG_WEB_SSE_LINE_EXTRA 7u
/* "id: ", a 64-bit number, its newline and the blank line that ends the
 * event: the room kept for them from the start. */
#define WSG_WEB_SSE_TAIL_MAX 26u
/* "data: (N bytes of log missed)\n" with a 64-bit N. */
#define WSG_WEB_SSE_NOTE_MAX 64u
/* The smallest buffer an event is packed into: the head, a note, one
 * line (cut to nothing if it must) and the tail. */
#define WSG_WEB_SSE_LOG_MIN                                                   \
    (WSG_WEB_SSE_HEAD_LEN + WSG_WEB_SSE_NOTE_MAX + WSG_WEB_SSE_LINE_EXTRA +   \
     WSG_WEB_SSE_TAIL_MAX)

/* The log as the stream reads it: the byte at log offset o is at
 * buf[o % size]; the bytes from oldest up to end (not included) are
 * there, the older ones were written over. Lines end with '\n'. */
struct wsg_web_ring {
    const char *buf;
    size_t size;
    uint64_t oldest;
    uint64_t end;
};

/* The next "log" event for a reader at log offset *off, packed into out
 * (cap bytes):
 *   event: log
 *   data: (N bytes of log missed)    when *off is older than r->oldest
 *   data: LINE                       as many whole lines as fit
 *   id: OFFSET                       where the reader is after it
 *   (a blank line)
 * A line longer than a whole event is cut to fit and its rest skipped;
 * a CR in a line, which would end an SSE line, is sent as a space. After
 * a note the reader goes on at the first whole line kept. Returns the
 * event's length, never more than cap, with *off moved past what it
 * carries (ahead whenever *off < r->end); 0 when cap is less than
 * WSG_WEB_SSE_LOG_MIN (nothing written, *off as it was). */
size_t wsg_web_sse_log(char *out, size_t cap, const struct wsg_web_ring *r,
                       uint64_t *off);

#endif
