/*
 * What a "log" event packed by wsg_web_sse_log (src/daemon/web_sse.h)
 * must be, checked against the ring it was packed from, for its unit test
 * (test_web_sse) and its fuzz harness (fuzz_sse): within its buffer; "event:
 * log", "data: " lines with neither CR nor LF in them, "id: N" and a blank
 * line, nothing else; the note of what was missed exactly when the reader
 * was behind the ring; then the log's lines in order from where the reader
 * was (CRs as spaces), each whole but for a first line longer than the
 * event could hold, cut; as many as fit, the next one not; the id where
 * the reader is after them, and ahead of where it was. The caller checks
 * that nothing past cap was written.
 */
#ifndef WSG_TEST_SSE_CHECK_H
#define WSG_TEST_SSE_CHECK_H

#include <stdint.h>
#include <stdio.h>
#include <string.h>

#include "web_sse.h"

/* NULL when the event of len bytes in out (cap bytes; the reader was at
 * before, is at after) is what it must be; else what is wrong. */
static inline const char *sse_check(const char *out, size_t len, size_t cap,
                                    const struct wsg_web_ring *r,
                                    uint64_t before, uint64_t after)
{
    uint64_t oldest = r->oldest, pos = before;
    size_t i = 0, before_id = 0;
    int content = 0;

    if (len > cap)
        return "longer than its buffer";
    if (cap < WSG_WEB_SSE_LOG_MIN)
        return len == 0 && after == before ? NULL
                                           : "packed into a buffer too small";
    if (len == 0)
        return "nothing packed into a buffer large enough";
    /* The ring's bytes, as web_sse.h says they are read. */
    if (oldest > r->end)
        oldest = r->end;
    if (!r->buf || r->size == 0)
        oldest = r->end;
    else if (r->end - oldest > r->size)
        oldest = r->end - r->size;

    if (len < 11 || memcmp(out, "event: log\n", 11) != 0)
        return "no event: log line first";
    i = 11;
    if (before < oldest) {
        char note[64];
        int n =
            snprintf(note, sizeof note, "data: (%llu bytes of log missed)\n",
                     (unsigned long long)(oldest - before));

        if (n <= 0 || len - i < (size_t)n || memcmp(out + i, note, (size_t)n))
            return "no note of what was missed, or a wrong one";
        i += (size_t)n;
        pos = oldest;
        while (pos < r->end && r->buf[pos++ % r->size] != '\n')
            ;
        content = 1;
    }
    while (len - i >= 6 && memcmp(out + i, "data: ", 6) == 0) {
        const char *d = out + i + 6;
        const char *eol = memchr(d, '\n', len - i - 6);
        size_t dl, el = 0, k;

        if (!eol)
            return "a data line without its newline";
        dl = (size_t)(eol - d);
        if (memchr(d, '\r', dl))
            return "a CR in a data line";
        if (pos >= r->end)
            return "a line past the end of the log";
        while (pos + el < r->end && r->buf[(pos + el) % r->size] != '\n')
            el++;
        /* Whole, or cut as the event's first line. */
        if (dl > el || (dl < el && content))
            return "a line is not the log's next line";
        for (k = 0; k < dl; k++) {
            char c = r->buf[(pos + k) % r->size];

            if (d[k] != (c == '\r' ? ' ' : c))
                return "a line's bytes are not the log's";
        }
        /* A cut line could not have fitted whole, and fills the event. */
        if (dl < el &&
            i + WSG_WEB_SSE_LINE_EXTRA + el + WSG_WEB_SSE_TAIL_MAX <= cap)
            return "a line cut that would have fitted";
        if (dl < el &&
            i + WSG_WEB_SSE_LINE_EXTRA + dl + WSG_WEB_SSE_TAIL_MAX != cap)
            return "a line cut shorter than the room left";
        pos = pos + el < r->end ? pos + el + 1 : pos + el;
        content = 1;
        i += 6 + dl + 1;
    }
    before_id = i;
    {
        char id[40];
        int n =
            snprintf(id, sizeof id, "id: %llu\n\n", (unsigned long long)after);

        if (n <= 0 || len - i != (size_t)n || memcmp(out + i, id, (size_t)n))
            return "not the id line and the blank line last";
    }
    if (after != pos && !(before > r->end && after == before))
        return "the id is not where the lines end";
    if (before < r->end && after <= before)
        return "no progress";
    /* As many whole lines as fit: the next one did not. */
    if (pos < r->end) {
        size_t nl = 0;

        while (pos + nl < r->end && r->buf[(pos + nl) % r->size] != '\n')
            nl++;
        if (!content)
            return "no line taken though one was there";
        if (before_id + WSG_WEB_SSE_LINE_EXTRA + nl + WSG_WEB_SSE_TAIL_MAX <=
            cap)
            return "the next line would have fitted";
    }
    return NULL;
}

#endif
