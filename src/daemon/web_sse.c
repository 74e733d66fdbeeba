/*
 * Packing the communication log into the event stream's "log" events
 * (web_sse.h). Every byte goes into the buffer through put() or
 * put_ring(), which check what is left before they write: the sizes
 * worked out for the lines only decide where an event ends, and no
 * mistake in them can take a write past the buffer. The room for the id
 * line is kept from the start, so an event always ends well-formed.
 */
#include "web_sse.h"

#include <stdio.h>
#include <string.h>

/* An event being packed: used <= cap always. */
struct sse_out {
    char *p;
    size_t cap;
    size_t used;
};

static int put(struct sse_out *o, const char *s, size_t n)
{
    if (n > o->cap - o->used)
        return -1;
    memcpy(o->p + o->used, s, n);
    o->used += n;
    return 0;
}

/* n bytes of the ring from log offset at (n <= its size). A CR would end
 * the SSE line for a browser, and what follows it would be read as a
 * field of its own (an id, an event name): it goes out as a space. */
static int put_ring(struct sse_out *o, const struct wsg_web_ring *r,
                    uint64_t at, size_t n)
{
    size_t pos, first, i;

    if (n > r->size || n > o->cap - o->used)
        return -1;
    pos = (size_t)(at % r->size);
    first = r->size - pos < n ? r->size - pos : n;
    memcpy(o->p + o->used, r->buf + pos, first);
    memcpy(o->p + o->used + first, r->buf, n - first);
    for (i = o->used; i < o->used + n; i++)
        if (o->p[i] == '\r')
            o->p[i] = ' ';
    o->used += n;
    return 0;
}

size_t wsg_web_sse_log(char *out, size_t cap, const struct wsg_web_ring *r,
                       uint64_t *off)
{
    static const char head[] = "event: log\n";
    struct sse_out o = {out, cap, 0};
    uint64_t oldest = r->oldest, at = *off;
    char text[WSG_WEB_SSE_NOTE_MAX];
    int content = 0, n;

    if (cap < WSG_WEB_SSE_LOG_MIN)
        return 0;
    /* Only what the ring can hold is read, whatever the caller says. */
    if (oldest > r->end)
        oldest = r->end;
    if (!r->buf || r->size == 0)
        oldest = r->end;
    else if (r->end - oldest > r->size)
        oldest = r->end - r->size;

    put(&o, head, sizeof head - 1);
    if (at < oldest) {
        /* Fell behind the ring: told how much, and on at the first line
         * that starts in it (its oldest byte may be inside a line). */
        n = snprintf(text, sizeof text, "data: (%llu bytes of log missed)\n",
                     (unsigned long long)(oldest - at));
        if (n > 0 && (size_t)n < sizeof text)
            put(&o, text, (size_t)n);
        at = oldest;
        while (at < r->end && r->buf[at++ % r->size] != '\n')
            ;
        content = 1;
    }
    while (at < r->end) {
        uint64_t eol = at;
        size_t len, room;

        while (eol < r->end && r->buf[eol % r->size] != '\n')
            eol++;
        len = (size_t)(eol - at);
        if (o.cap - o.used < WSG_WEB_SSE_LINE_EXTRA + WSG_WEB_SSE_TAIL_MAX)
            break;
        room = o.cap - o.used - WSG_WEB_SSE_LINE_EXTRA - WSG_WEB_SSE_TAIL_MAX;
        if (len > room) {
            if (content)
                break;  /* the next event takes it */
            len = room; /* longer than an event: cut */
        }
        if (put(&o, "data: ", 6) < 0 || put_ring(&o, r, at, len) < 0 ||
            put(&o, "\n", 1) < 0)
            return 0; /* cannot happen: the room was counted */
        /* A line at the end without its newline (the ring is fed whole
         * lines) is taken as it is. */
        at = eol < r->end ? eol + 1 : eol;
        content = 1;
    }
    /* The offset as the event's id: a browser that reconnects sends it
     * back (Last-Event-ID) and goes on where it was. */
    n = snprintf(text, sizeof text, "id: %llu\n\n", (unsigned long long)at);
    if (n < 0 || (size_t)n >= sizeof text || put(&o, text, (size_t)n) < 0)
        return 0; /* cannot happen: its room was kept */
    *off = at;
    return o.used;
}
