/*
 * integ_web: the gripper's web page (--web) against the real daemon.
 *
 * - the ready line ends with web=127.0.0.1:PORT;
 * - GET / is the page, and its script and style are served with their
 *   types; HEAD answers without a body; an unknown path is 404, a wrong
 *   method 405 with Allow, a POST from another site's page (Origin) 403,
 *   a body over 4 KiB 413, chunked too (not a reset; a chunked form
 *   within the cap is taken);
 * - a form is read only as its media type: application/x-www-form-
 *   urlencoded exactly, case aside, with parameters; ...XYZ, ...-not,
 *   text/plain and text/plainfoo are 415 and change nothing; routes that
 *   take no form do not decode one (40 fields to POST /stop or GET
 *   /state.json, from=nothing to GET /script/output: no effect), one that
 *   does refuses 40 fields (400);
 * - a NUL or control character decoded from a form's name or value, or
 *   the URL's path or query, is 400 (line=part+25%00 sets no part,
 *   /state.json%00.txt is not /state.json);
 * - GET /state.json is the control channel's state byte for byte, ended
 *   by a newline (time paused, so the two cannot differ in time); GET
 *   /info.json has the model's stroke and every flag's name by bit;
 * - /events: a state event at once; then, with nothing happening, none,
 *   and the daemon does not wake (the scheduler's "wakes" stays, no
 *   context switches to speak of) for 2 s with the stream open;
 * - a homing over TCP is pushed as it runs: many events while moving, no
 *   more than one per 50 ms, the last the final state, then silence;
 * - POST /stop stops a motion (40h: AXIS_STOPPED, not MOVING, at once; the
 *   motion ends E_CMD_ABORTED); POST /ack clears a FAST STOP (40h and
 *   the control channel's state);
 * - 15 streams at once (16 with the first: as many as an address may
 *   have) all see a change; closed by their clients they are freed (the
 *   daemon's descriptors come back) with no change to push;
 * - the daemon exits 0 with a stream open.
 *
 * Built without libmicrohttpd (WSG_TEST_HAVE_WEB 0) it is skipped.
 */
#include "check.h"
#include "emu.h"
#include "emu_ctl.h"
#include "emu_http.h"

#include <dirent.h>
#include <stdlib.h>
#include <string.h>

#ifndef WSG_TEST_HAVE_WEB
#define WSG_TEST_HAVE_WEB 0
#endif

/* How many event streams at once in the fan-out test: with the test's
 * own, as many as one address may have (WSG_WEB_PEER_STREAMS_MAX). */
#define NSTREAMS 15
/* Room for one event's name and data (a log event is up to 16 KiB). */
#define EV_MAX 20000
/* The largest request body the daemon takes (WSG_WEB_BODY_MAX). */
#define BODY_MAX 4096

static const char *const args[] = {"--tcp",       "127.0.0.1:0", "--control",
                                   "127.0.0.1:0", "--web",       "127.0.0.1:0",
                                   NULL};

/* A form body's header. */
#define FORM "Content-Type: application/x-www-form-urlencoded\r\n"

static char web[64]; /* the web= field */
static struct http_answer ans;

static int get(const char *method, const char *path, const char *headers,
               const char *body)
{
    if (http_request(web, method, path, headers, body, &ans, EMU_REPLY_MS) < 0)
        return -1;
    return ans.status;
}

/* The next event named want within timeout_ms: 1 (its data in data), 0
 * none, -1 the stream ended. Events of the other kind ("state" or "log")
 * are passed over; one of another name fails the check. */
static int next_event(struct http_stream *s, const char *want, char *data,
                      int timeout_ms)
{
    char name[64];
    double end = emu_now_ms() + timeout_ms, left;
    int r;

    for (;;) {
        left = end - emu_now_ms();
        r = http_stream_event(s, name, sizeof name, data, EV_MAX,
                              left > 0 ? (int)left : 0);
        if (r != 1 || strcmp(name, want) == 0)
            return r;
        CHECK(strcmp(name, "state") == 0 || strcmp(name, "log") == 0);
    }
}

static int next_state(struct http_stream *s, char *data, int timeout_ms)
{
    return next_event(s, "state", data, timeout_ms);
}

static int has_flag(const char *json, const char *name)
{
    char quoted[64];

    snprintf(quoted, sizeof quoted, "\"%s\"", name);
    return strstr(json, quoted) != NULL;
}

/* Descriptors the daemon holds. */
static int fd_count(pid_t pid)
{
    char path[64];
    struct dirent *d;
    DIR *dir;
    int n = 0;

    snprintf(path, sizeof path, "/proc/%d/fd", (int)pid);
    dir = opendir(path);
    if (!dir)
        return -1;
    while ((d = readdir(dir)) != NULL)
        if (d->d_name[0] != '.')
            n++;
    closedir(dir);
    return n;
}

static void test_ready(const struct emu *e)
{
    const char *field = strstr(e->line, " web=");

    CHECK(strncmp(web, "127.0.0.1:", 10) == 0 && atoi(web + 10) > 0);
    /* The last field of the line. */
    CHECK(field && !strchr(field + 1, ' '));
}

static void test_files(void)
{
    char v[128];

    CHECK_EQ(get("GET", "/", NULL, NULL), 200);
    CHECK(http_header(&ans, "Content-Type", v, sizeof v) &&
          strncmp(v, "text/html", 9) == 0);
    CHECK(strncmp(ans.body, "<!DOCTYPE html>", 15) == 0);
    CHECK(strstr(ans.body, "/app.js") && strstr(ans.body, "/style.css"));
    CHECK(strstr(ans.body, "id=\"stop\"") && strstr(ans.body, "id=\"ack\""));
    CHECK_EQ(get("GET", "/index.html", NULL, NULL), 200);
    CHECK_EQ(get("GET", "/app.js", NULL, NULL), 200);
    CHECK(http_header(&ans, "Content-Type", v, sizeof v) &&
          strncmp(v, "text/javascript", 15) == 0);
    CHECK(strstr(ans.body, "new EventSource('/events')") != NULL);
    CHECK_EQ(get("GET", "/style.css", NULL, NULL), 200);
    CHECK(http_header(&ans, "Content-Type", v, sizeof v) &&
          strncmp(v, "text/css", 8) == 0);
    CHECK_EQ(get("HEAD", "/", NULL, NULL), 200);
    CHECK_EQ(ans.body_len, 0);
}

static void test_errors(void)
{
    char v[128], big[BODY_MAX + 2];

    CHECK_EQ(get("GET", "/nothing", NULL, NULL), 404);
    CHECK_EQ(get("GET", "/../etc/passwd", NULL, NULL), 404);
    CHECK_EQ(get("DELETE", "/state.json", NULL, NULL), 405);
    CHECK(http_header(&ans, "Allow", v, sizeof v) &&
          strcmp(v, "GET, HEAD") == 0);
    CHECK_EQ(get("GET", "/stop", NULL, NULL), 405);
    CHECK(http_header(&ans, "Allow", v, sizeof v) && strcmp(v, "POST") == 0);
    CHECK_EQ(get("POST", "/events", NULL, NULL), 405);
    CHECK_EQ(
        get("POST", "/stop", "Origin: http://elsewhere.example\r\n", NULL),
        403);
    memset(big, 'x', sizeof big - 1);
    big[sizeof big - 1] = '\0';
    CHECK_EQ(get("POST", "/ack", NULL, big), 413);
}

static void test_state(struct ctl *k)
{
    const char *js;
    char v[128];

    CMD_OK(k, "time pause");
    CHECK_EQ(get("GET", "/state.json", NULL, NULL), 200);
    CHECK(http_header(&ans, "Content-Type", v, sizeof v) &&
          strcmp(v, "application/json") == 0);
    js = ctl_cmd(k, "state");
    /* The channel's object, ended by a newline as its line is. */
    CHECK(strncmp(js, "ok ", 3) == 0 &&
          strlen(ans.body) == strlen(js + 3) + 1 &&
          strncmp(js + 3, ans.body, strlen(js + 3)) == 0 &&
          ans.body[strlen(js + 3)] == '\n');
    if (strncmp(js, "ok ", 3) != 0 || strlen(ans.body) != strlen(js + 3) + 1 ||
        strncmp(js + 3, ans.body, strlen(js + 3)) != 0)
        fprintf(stderr, "control: %s\nweb:     %s\n", js, ans.body);
    CMD_OK(k, "time resume");

    CHECK_EQ(get("GET", "/info.json", NULL, NULL), 200);
    CHECK_NEAR(ctl_json_num(ans.body, "stroke"), 110.0, 1e-9);
    CHECK(strstr(ans.body, "\"flag_names\":[\"referenced\",\"moving\",") !=
          NULL);
    CHECK(strstr(ans.body, "\"fast_stop\"") != NULL);
}

/* Idle with a stream open: nothing pushed, nothing woken. */
static void test_idle(struct emu *e, struct ctl *k, struct http_stream *s)
{
    char data[EV_MAX];
    long sw0, sw1, t0, t1;
    double wakes0, wakes1;

    wakes0 = ctl_json_num(ctl_cmd(k, "stats"), "wakes");
    emu_sleep_ms(100);
    REQUIRE(emu_proc_activity(e->pid, &sw0, &t0) == 0);
    CHECK_EQ(next_state(s, data, emu_ms(2000)), 0);
    REQUIRE(emu_proc_activity(e->pid, &sw1, &t1) == 0);
    wakes1 = ctl_json_num(ctl_cmd(k, "stats"), "wakes");
    CHECK(wakes0 >= 0);
    CHECK_EQ(wakes1, wakes0);
    /* A timer of the web page's (MHD's timeouts, the pushes) would show
     * as switches too: a handful at most, as for any idle daemon. */
    CHECK(sw1 - sw0 <= 5);
    CHECK(t1 - t0 <= 2);
}

/* A homing at half speed (about 1.8 s) watched through the stream. */
static void test_push(struct emu_client *c, struct ctl *k,
                      struct http_stream *s)
{
    char data[EV_MAX], last[EV_MAX] = "";
    struct wsg_client_frame f;
    uint8_t dir = 0;
    int moving = 0, n = 0, r;
    double first = 0, t = 0;

    CMD_OK(k, "time scale 0.5");
    CHECK_EQ(emu_request(c, WSG_CMD_HOMING, &dir, 1, NULL, EMU_REPLY_MS),
             WSG_E_CMD_PENDING);
    while ((r = next_state(s, data, EMU_HOMING_MS * 2)) == 1) {
        t = emu_now_ms();
        if (n++ == 0)
            first = t;
        snprintf(last, sizeof last, "%s", data);
        if (has_flag(data, "moving"))
            moving++;
        else if (has_flag(data, "referenced"))
            break;
    }
    CHECK_EQ(r, 1);
    /* About 35 at 20 a second; many fewer would not be a live view. */
    CHECK(moving >= 8);
    /* Never more than one per 50 ms (a little slack for the reads). */
    CHECK((double)(n - 1) <= (t - first + 100.0) / 50.0);
    if (moving < 8 || (double)(n - 1) > (t - first + 100.0) / 50.0)
        fprintf(stderr, "%d events, %d moving, over %.0f ms\n", n, moving,
                t - first);
    CHECK_NEAR(ctl_json_num(last, "width"), 110.0, 1e-9);
    CHECK_NEAR(ctl_json_num(last, "speed"), 0.0, 1e-9);
    CHECK_EQ(emu_recv_id(c, WSG_CMD_HOMING, &f, EMU_HOMING_MS * 2), 1);
    CHECK_EQ(f.status, WSG_E_SUCCESS);
    /* Done: nothing more to push. */
    CHECK_EQ(next_state(s, data, EMU_QUIET_MS), 0);
    CMD_OK(k, "time scale 1");
}

static void test_stop_ack(struct emu_client *c, struct ctl *k,
                          struct http_stream *s)
{
    struct wsg_client_frame f;
    uint8_t p[16];
    size_t n = emu_move_payload(p, 0, 20.0f, 10.0f);
    uint32_t flags = 0;
    char data[EV_MAX];

    /* STOP: a slow move stopped from the page. */
    CMD_OK(k, "time scale 0.2");
    CHECK_EQ(emu_request(c, WSG_CMD_PREPOSITION, p, n, NULL, EMU_REPLY_MS),
             WSG_E_CMD_PENDING);
    CHECK(emu_wait_flags(c, WSG_SF_MOVING, WSG_SF_MOVING, EMU_MOVE_MS, NULL) ==
          0);
    CHECK_EQ(get("POST", "/stop", NULL, NULL), 200);
    CHECK(strcmp(ans.body, "{\"status\":\"E_SUCCESS\"}") == 0);
    CHECK(emu_get_flags(c, &flags) == 0);
    CHECK(flags & WSG_SF_AXIS_STOPPED);
    CHECK(!(flags & WSG_SF_MOVING));
    CHECK_EQ(emu_recv_id(c, WSG_CMD_PREPOSITION, &f, EMU_MOVE_MS), 1);
    CHECK_EQ(f.status, WSG_E_CMD_ABORTED);
    CMD_OK(k, "time scale 1");

    /* ACK: a FAST STOP acknowledged from the page; a POST from the page's
     * own origin is taken. */
    CHECK_EQ(emu_request(c, WSG_CMD_FAST_STOP, NULL, 0, NULL, EMU_REPLY_MS),
             WSG_E_SUCCESS);
    CHECK(emu_get_flags(c, &flags) == 0 && (flags & WSG_SF_FAST_STOP));
    CHECK(has_flag(ctl_cmd(k, "state"), "fast_stop"));
    {
        char origin[128];

        snprintf(origin, sizeof origin, "Origin: http://%s\r\n", web);
        CHECK_EQ(get("POST", "/ack", origin, NULL), 200);
    }
    CHECK(strcmp(ans.body, "{\"status\":\"E_SUCCESS\"}") == 0);
    CHECK(emu_get_flags(c, &flags) == 0 && !(flags & WSG_SF_FAST_STOP));
    CHECK(!has_flag(ctl_cmd(k, "state"), "fast_stop"));
    /* The stream saw it come and go (the newest state at least). */
    while (next_state(s, data, EMU_QUIET_MS * 2) == 1)
        ;
    CHECK(!has_flag(data, "fast_stop"));
}

/* The next "log" event's lines within timeout_ms: 1, or 0 none. */
static int next_log(struct http_stream *s, char *data, int timeout_ms)
{
    return next_event(s, "log", data, timeout_ms) == 1;
}

/* Wait for log lines containing a and then b (in one event or two); 1
 * when both were seen. */
static int see_log(struct http_stream *s, const char *a, const char *b)
{
    char data[EV_MAX];
    double end = emu_now_ms() + EMU_REPLY_MS;
    const char *at;
    int seen_a = 0;

    while (emu_now_ms() < end) {
        if (!next_log(s, data, EMU_REPLY_MS))
            continue;
        at = data;
        if (!seen_a && (at = strstr(data, a)) != NULL)
            seen_a = 1;
        if (seen_a && at && strstr(at, b))
            return 1;
    }
    return 0;
}

/* The communication log as it happens: a packet in and its answer out,
 * in the --log format; a page reconnecting with the last id it had goes
 * on after it, one opened anew shows what came before. */
static void test_log(struct emu_client *c)
{
    struct http_stream s, again;
    char hdr[64], data[EV_MAX];
    float w;

    REQUIRE(http_stream_open(&s, web, "/events", EMU_REPLY_MS) == 0);
    CHECK(emu_get_float(c, WSG_CMD_GET_WIDTH, &w) == 0);
    CHECK(see_log(&s, " in 43h GetOpeningWidth\n",
                  " out 43h GetOpeningWidth E_SUCCESS width="));
    CHECK(s.id[0] != '\0');
    /* The sidebar's STOP and ACK are events of the log, as 22h and 24h. */
    CHECK_EQ(get("POST", "/stop", NULL, NULL), 200);
    CHECK(see_log(&s, " web event stop", ""));
    CHECK_EQ(get("POST", "/ack", NULL, NULL), 200);
    CHECK(see_log(&s, " web event ack nothing to clear", ""));
    http_stream_close(&s);

    /* Reconnected with its last id: only what is new. */
    snprintf(hdr, sizeof hdr, "Last-Event-ID: %s\r\n", s.id);
    CHECK(emu_get_float(c, WSG_CMD_GET_SPEED, &w) == 0);
    REQUIRE(http_stream_open_with(&again, web, "/events", hdr, EMU_REPLY_MS) ==
            0);
    CHECK_EQ(next_log(&again, data, EMU_REPLY_MS), 1);
    CHECK(strstr(data, " 44h ") != NULL);
    CHECK(strstr(data, " 43h ") == NULL);
    http_stream_close(&again);

    /* A new page: the history kept. */
    REQUIRE(http_stream_open(&again, web, "/events", EMU_REPLY_MS) == 0);
    CHECK_EQ(next_log(&again, data, EMU_REPLY_MS), 1);
    CHECK(strstr(data, " 43h ") != NULL && strstr(data, " 44h ") != NULL);
    http_stream_close(&again);
}

/* The scenario panel: the control channel's commands, answered with its
 * line. */
static void test_control(struct ctl *k)
{
    CHECK_EQ(get("POST", "/control", FORM, "line=part+25+80"), 200);
    CHECK(strcmp(ans.body, "{\"ok\":true,\"answer\":\"ok part 25 80\"}") == 0);
    CHECK(strstr(ctl_cmd(k, "state"), "\"part\":{\"width\":25.000"));
    CHECK_EQ(get("POST", "/control", FORM, "line=obstacle+12.5"), 200);
    CHECK(strstr(ctl_cmd(k, "state"), "\"obstacle\":12.500"));
    CHECK_EQ(get("POST", "/control", FORM, "line=obstacle+none"), 200);
    CHECK(strstr(ctl_cmd(k, "state"), "\"obstacle\":null"));
    CHECK_EQ(get("POST", "/control", FORM, "line=part+none"), 200);
    CHECK_EQ(get("POST", "/control", FORM, "line=part+wide"), 400);
    CHECK(strstr(ans.body, "\"ok\":false,\"answer\":\"error ") != NULL);
    CHECK_EQ(get("POST", "/control", FORM, "line="), 400);
    CHECK(strstr(ans.body, "\"error\":\"no command") != NULL);
    CHECK_EQ(get("POST", "/control", FORM, "line=time%0Atime"), 400);
    CHECK_EQ(get("GET", "/control", NULL, NULL), 405);
}

/* A request sent as it is, with a chunked body of n bytes of 'x' in
 * chunks of 1000 (form: the bytes are the form's, not x's): the status,
 * or -1 (no answer, the connection was reset). */
static int chunked(const char *path, const char *type, const char *form,
                   size_t n)
{
    static char msg[16384];
    size_t used, off, k;

    used = (size_t)snprintf(msg, sizeof msg,
                            "POST %s HTTP/1.1\r\nHost: %s\r\n"
                            "Connection: close\r\n%s"
                            "Transfer-Encoding: chunked\r\n\r\n",
                            path, web, type ? type : "");
    if (form)
        n = strlen(form);
    for (off = 0; off < n && used + 1100 < sizeof msg; off += k) {
        k = n - off < 1000 ? n - off : 1000;
        used += (size_t)snprintf(msg + used, sizeof msg - used, "%zx\r\n", k);
        if (form)
            memcpy(msg + used, form + off, k);
        else
            memset(msg + used, 'x', k);
        used += k;
        memcpy(msg + used, "\r\n", 2);
        used += 2;
    }
    used += (size_t)snprintf(msg + used, sizeof msg - used, "0\r\n\r\n");
    if (http_exchange(web, msg, used, &ans, EMU_REPLY_MS) < 0)
        return -1;
    return ans.status;
}

/* What a request carries, checked: a chunked body over the cap is 413
 * as a Content-Length one is (not a reset); a form is decoded only where
 * a route takes one, and only when its type is exactly a form's; a NUL
 * or control character anywhere in the decoded URL or form is 400. */
static void test_bodies(struct ctl *k)
{
    char many[1024] = "a=1";
    int i;

    /* Chunked: a form within the cap is taken, a body over it 413. */
    CHECK_EQ(chunked("/control", FORM, "line=part+25", 0), 200);
    CHECK(strstr(ctl_cmd(k, "state"), "\"part\":{\"width\":25.000"));
    CHECK_EQ(get("POST", "/control", FORM, "line=part+none"), 200);
    CHECK_EQ(chunked("/ack", NULL, NULL, BODY_MAX), 200);
    CHECK_EQ(chunked("/ack", NULL, NULL, BODY_MAX + 1), 413);
    CHECK(strstr(ans.body, "\"error\":\"body larger than 4096 bytes\"") !=
          NULL);
    CHECK_EQ(chunked("/control", FORM, NULL, 3 * BODY_MAX), 413);

    /* The form's media type, exactly: case aside, with parameters. */
    CHECK_EQ(get("POST", "/control",
                 "Content-Type: application/x-www-form-urlencodedXYZ\r\n",
                 "line=part+25"),
             415);
    CHECK_EQ(get("POST", "/control", "Content-Type: text/plainfoo\r\n",
                 "line=part+25"),
             415);
    CHECK_EQ(get("POST", "/control", "Content-Type: text/plain\r\n",
                 "line=part+25"),
             415);
    CHECK_EQ(get("POST", "/control",
                 "Content-Type: application/x-www-form-urlencoded-not\r\n",
                 "line=part+25"),
             415);
    CHECK(strstr(ctl_cmd(k, "state"), "\"part\":null"));
    CHECK_EQ(get("POST", "/control",
                 "Content-Type: Application/X-WWW-Form-Urlencoded ; "
                 "charset=UTF-8\r\n",
                 "line=part+25"),
             200);
    CHECK_EQ(get("POST", "/control",
                 "Content-Type: application/x-www-form-urlencoded;"
                 "charset=UTF-8\r\n",
                 "line=part+none"),
             200);
    CHECK(strstr(ctl_cmd(k, "state"), "\"part\":null"));
    /* No body: no type needed (the fields may be in the query). */
    CHECK_EQ(get("POST", "/control?line=part+none", NULL, NULL), 200);

    /* Routes that take no form do not decode one: more fields than a
     * form may have, or a field a handler would read, change nothing. */
    for (i = 1; i < 40; i++)
        snprintf(many + strlen(many), sizeof many - strlen(many), "&f%d=1", i);
    CHECK_EQ(get("POST", "/stop", FORM, many), 200);
    CHECK_EQ(get("GET", "/state.json", FORM, many), 200);
    CHECK_EQ(get("GET", "/script/output?from=0", FORM, "from=nothing"), 200);
    CHECK(strstr(ans.body, "\"from\":0,") != NULL);
    /* ... where one is taken, too many fields are refused. */
    CHECK_EQ(get("POST", "/control", FORM, many), 400);

    /* A NUL or control character, decoded, in a form or the URL. */
    CHECK_EQ(get("POST", "/control", FORM, "line=part+25%00"), 400);
    CHECK_EQ(get("POST", "/control", FORM, "li%00ne=part+25"), 400);
    CHECK_EQ(get("POST", "/control", FORM, "line=part+25%01"), 400);
    CHECK_EQ(get("POST", "/control?line=part+25%00", NULL, NULL), 400);
    CHECK(strstr(ctl_cmd(k, "state"), "\"part\":null"));
    CHECK_EQ(get("GET", "/state.json%00.txt", NULL, NULL), 400);
    CHECK_EQ(get("GET", "/state.json?x=%1f", NULL, NULL), 400);
    CHECK_EQ(get("GET", "/state.json?x=%20", NULL, NULL), 200);
}

/* On loopback, another site's name in Host is not answered (DNS
 * rebinding); loopback names are. */
static void test_host(void)
{
    char host[96];
    const char *port = strrchr(web, ':');

    CHECK_EQ(get("GET", "/state.json", "Host: attacker.example\r\n", NULL),
             421);
    snprintf(host, sizeof host, "Host: localhost%s\r\n", port);
    CHECK_EQ(get("GET", "/state.json", host, NULL), 200);
    snprintf(host, sizeof host, "Host: [::1]%s\r\n", port);
    CHECK_EQ(get("GET", "/state.json", host, NULL), 200);
    snprintf(host, sizeof host, "Host: localhost.attacker.example%s\r\n",
             port);
    CHECK_EQ(get("GET", "/state.json", host, NULL), 421);
}

/* 200 requests in the server's hands at once, all answered, while the
 * gripper still answers on its own interface. */
static void test_load(struct emu_client *c)
{
    float w;

    CHECK_EQ(http_load(web, "/state.json", 200, EMU_REPLY_MS * 4), 200);
    CHECK_EQ(http_load(web, "/", 200, EMU_REPLY_MS * 4), 200);
    CHECK(emu_get_float(c, WSG_CMD_GET_WIDTH, &w) == 0);
}

/* Many streams see one change; closed by their clients, all are freed
 * without a change to push them out. */
static void test_many(struct emu *e, struct ctl *k)
{
    struct http_stream *s = calloc(NSTREAMS, sizeof *s);
    char data[EV_MAX];
    int base, i, got = 0, fds = -1;
    double deadline;

    REQUIRE(s != NULL);
    base = fd_count(e->pid);
    CHECK(base > 0);
    for (i = 0; i < NSTREAMS; i++) {
        REQUIRE(http_stream_open(&s[i], web, "/events", EMU_REPLY_MS) == 0);
        CHECK_EQ(s[i].status, 200);
        CHECK_EQ(next_state(&s[i], data, EMU_REPLY_MS), 1);
    }
    CMD_OK(k, "part 30");
    for (i = 0; i < NSTREAMS; i++)
        if (next_state(&s[i], data, EMU_REPLY_MS) == 1 &&
            strstr(data, "\"part\":{\"width\":30.000"))
            got++;
    CHECK_EQ(got, NSTREAMS);
    for (i = 0; i < NSTREAMS; i++)
        http_stream_close(&s[i]);
    deadline = emu_now_ms() + EMU_REPLY_MS;
    while (emu_now_ms() < deadline && (fds = fd_count(e->pid)) > base)
        emu_sleep_ms(20);
    CHECK_EQ(fds, base);
    CMD_OK(k, "part none");
    free(s);
}

int main(int argc, char **argv)
{
    const char *exe = emu_exe(argc, argv);
    static struct http_stream s;
    char data[EV_MAX];
    struct emu_client c;
    struct emu e;
    struct ctl k;

    if (!WSG_TEST_HAVE_WEB)
        test_skip("wsgemu was built without libmicrohttpd");
    REQUIRE(emu_start(&e, exe, args) == 0);
    REQUIRE(emu_field(&e, "web", web, sizeof web) != NULL);
    REQUIRE(ctl_open(&k, &e) == 0);
    REQUIRE(emu_open(&c, &e, &emu_tcp) == 0);

    test_ready(&e);
    REQUIRE(http_stream_open(&s, web, "/events", EMU_REPLY_MS) == 0);
    CHECK_EQ(s.status, 200);
    CHECK(strcmp(s.type, "text/event-stream") == 0);
    CHECK(s.chunked);
    REQUIRE(next_state(&s, data, EMU_REPLY_MS) == 1);
    CHECK_NEAR(ctl_json_num(data, "width"), 55.0, 1e-9);
    test_idle(&e, &k, &s);
    test_files();
    test_errors();
    test_state(&k);
    test_push(&c, &k, &s);
    test_stop_ack(&c, &k, &s);
    test_many(&e, &k);
    test_log(&c);
    test_control(&k);
    test_bodies(&k);
    test_host();
    test_load(&c);

    /* Closing with a stream open (suspended, waiting for a change). */
    emu_close(&c);
    ctl_close(&k);
    CHECK_EQ(emu_stop(&e), 0);
    http_stream_close(&s);
    TEST_EXIT();
}
