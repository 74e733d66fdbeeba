/*
 * An HTTP client for the tests of the daemon's web page (--web): plain
 * requests (one connection each, "Connection: close", the answer read to
 * its end), requests sent byte for byte as a test wrote them, and a
 * Server-Sent Events stream read event by event; from another loopback
 * address when a test needs a peer of its own. HTTP/1.1
 * as the daemon's server speaks it: chunked bodies are decoded, nothing
 * else of HTTP is needed. Every wait takes a timeout, as everywhere in
 * the integration tests.
 */
#ifndef WSG_TEST_EMU_HTTP_H
#define WSG_TEST_EMU_HTTP_H

#include <stddef.h>

#define HTTP_HEAD_MAX 4096u
#define HTTP_BODY_MAX 65536u

struct http_answer {
    int status;               /* 200; 0: no status line */
    char head[HTTP_HEAD_MAX]; /* the status line and headers */
    char body[HTTP_BODY_MAX]; /* decoded, NUL-terminated */
    size_t body_len;
};

/* METHOD PATH to addr ("127.0.0.1:PORT") with the extra header lines
 * headers (each ending in \r\n; NULL: none) and body (NULL: none; a
 * Content-Length is sent with it). 0, or -1 with a message on stderr. */
int http_request(const char *addr, const char *method, const char *path,
                 const char *headers, const char *body, struct http_answer *a,
                 int timeout_ms);
/* req sent to addr as it is (a request line and headers of the test's
 * own, e.g. HTTP/1.0 without a Host), the answer read to its end. 0, or
 * -1 with a message on stderr. */
int http_request_raw(const char *addr, const char *req, struct http_answer *a,
                     int timeout_ms);
/* The request req (len bytes, head and body, as they are) on a
 * connection of its own, and its answer read to the end: for requests
 * http_request does not make (a chunked body, bytes it would not send).
 * 0, or -1 (no answer: the connection was closed or reset without one). */
int http_exchange(const char *addr, const void *req, size_t len,
                  struct http_answer *a, int timeout_ms);
/* The value of header name in a (case-insensitive name) into buf; NULL
 * when absent. */
const char *http_header(const struct http_answer *a, const char *name,
                        char *buf, size_t cap);

/* 1 when text (len bytes) is one JSON value (RFC 8259) in valid UTF-8,
 * else 0. */
int http_json_valid(const char *text, size_t len);

/* Connect to addr: the socket, or -1 with a message on stderr. Every
 * connection of this client is made here. */
int http_open(const char *addr);
/* Make the connections from now on from the local address ip (e.g.
 * "127.0.0.2", a peer of its own for the server); NULL or "": the
 * system's choice again. */
void http_source(const char *ip);

/* An open GET whose body is read as it comes: an event stream. */
struct http_stream {
    int fd;
    int status;
    int chunked;
    char type[64];           /* its Content-Type; "" without one */
    char raw[HTTP_BODY_MAX]; /* received, not yet decoded */
    size_t raw_len;
    char text[HTTP_BODY_MAX]; /* decoded, not yet taken as events */
    size_t text_len;
    int eof;
    char id[32]; /* the last event id seen ("" none) */
};

/* Open GET path and read the answer's head. 0 (s->status set), or -1. */
int http_stream_open(struct http_stream *s, const char *addr, const char *path,
                     int timeout_ms);
/* The same with extra header lines ("Name: value\r\n" each). */
int http_stream_open_with(struct http_stream *s, const char *addr,
                          const char *path, const char *headers,
                          int timeout_ms);
/* The next whole event: its "event:" name into name and its "data:" into
 * data (both NUL-terminated, cut to fit). 1: one, 0: none within
 * timeout_ms, -1: the stream ended or failed. */
int http_stream_event(struct http_stream *s, char *name, size_t name_cap,
                      char *data, size_t data_cap, int timeout_ms);
/* The next whole event as it came: its lines, each with its newline,
 * without the blank line that ends it, into buf (NUL-terminated), its
 * length into len. Nothing of it is interpreted (s->id stays). 1: one,
 * 0: none within timeout_ms, -1: the stream ended or failed, or the event
 * does not fit in cap - 1 bytes. */
int http_stream_raw(struct http_stream *s, char *buf, size_t cap, size_t *len,
                    int timeout_ms);
void http_stream_close(struct http_stream *s);

/* n connections to addr at once, each with a GET path sent before any
 * answer is read; how many were answered 200 within timeout_ms. */
int http_load(const char *addr, const char *path, int n, int timeout_ms);

#endif
