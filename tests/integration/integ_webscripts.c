/*
 * integ_webscripts: the web page's scripting (--web with --script-dir)
 * against the real daemon.
 *
 * - files: a script uploaded (PUT: 201, again 200) is listed with its size
 *   (GET /scripts.json, sorted by name), downloaded as it was (GET, with
 *   Content-Disposition: attachment) and deleted (DELETE; then 404); no
 *   temporary file is left in the directory;
 * - names: ../x.lua, a/b.lua, %2e%2e%2fx.lua, .hidden.lua, x.txt and a
 *   name of 65 characters are refused (400) and nothing is written outside
 *   the directory; a symbolic link planted in the directory, pointing
 *   outside, is neither read, written, deleted nor run (403), and the file
 *   it points to is unchanged;
 * - names with a NUL or a control character, percent-encoded in the
 *   path, the query or the form (ping.lua%00.txt, ping.lua%0a): 400, and
 *   the name they would be cut to (ping.lua) is neither written, deleted
 *   nor run;
 * - caps: 256 KiB is taken, a Content-Length of one byte more refused
 *   (413) before the body is sent; the directory's bounds (--script-quota,
 *   --script-files): an upload past its bytes or count is refused (507;
 *   413 for one larger than the quota itself) and not written, a
 *   replacement counts for its new size;
 *   (413) before the body is sent; the same chunked: 256 KiB taken, a
 *   byte more answered 413 (not a reset) and nothing written;
 * - run: a script uploaded and run from the page (POST /script/run)
 *   registers its own command ID and answers it over TCP; the state shows
 *   it running (D19, "script"); what it prints comes in the event
 *   stream's log events; a second run while it runs is 409; POST
 *   /script/stop stops it (D19 cleared, its ID E_CMD_UNKNOWN again);
 * - failure: a script that raises an error shows the error and D20 in the
 *   state (and GET /script/status); one that does not compile is 422;
 * - control: POST /control's `script run` runs a script of the directory
 *   by name (as POST /script/run); a path outside it (/etc/passwd, a
 *   script that would print a marker, a file whose text a compile error
 *   would quote) is refused (400) and nothing of it runs or shows;
 * - race: runs of a name that another process keeps swapping between a
 *   file of the directory and a link to a script outside it each run the
 *   directory's file or are refused (403), never the file outside;
 *   an error as long as the host keeps, of control characters and a
 *   character cut in two, is still answered by the run (422) and GET
 *   /script/status, in valid JSON;
 * - without --script-dir every endpoint says so (409, naming the option).
 *
 * Built without libmicrohttpd (WSG_TEST_HAVE_WEB 0) it is skipped.
 */
#define _GNU_SOURCE /* mkdtemp, symlink, lstat */

#include "check.h"
#include "emu.h"
#include "emu_http.h"

#include <arpa/inet.h>
#include <dirent.h>
#include <errno.h>
#include <netinet/in.h>
#include <signal.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <sys/time.h>
#include <sys/wait.h>
#include <unistd.h>

#ifndef WSG_TEST_HAVE_WEB
#define WSG_TEST_HAVE_WEB 0
#endif

/* The upload cap (WSG_WEB_UPLOAD_MAX). */
#define UPLOAD_MAX (256 * 1024)
/* Room for one event's name and data (a log event is up to 16 KiB). */
#define EV_MAX 20000
/* The IDs the test's scripts register. */
#define ID_PING 0xB5
#define ID_FAIL 0xB6
/* How long a script's effect may take to show in the state: a bound
 * (the machine may be loaded), not an expectation. */
#define STATE_WAIT_MS emu_ms(10000)

/* Answers ID_PING with E_SUCCESS and "pong", after printing a line. */
static const char ping_lua[] = "-- ping.lua: answers B5h\n"
                               "cmd.register(0xB5)\n"
                               "print(\"hello from the web\")\n"
                               "while true do\n"
                               "  local id = cmd.read()\n"
                               "  cmd.send(id, etob(E_SUCCESS), \"pong\")\n"
                               "end\n";
/* Fails at its first packet. */
static const char fail_lua[] = "cmd.register(0xB6)\n"
                               "cmd.read()\n"
                               "error(\"asked to fail\")\n";

static char top_dir[256]; /* the test's directory */
static char dir[256];     /* the script directory, in it */
static char outside[256]; /* beside it, outside */
static char web[64];
static struct http_answer ans;

static int req(const char *method, const char *path, const char *body)
{
    if (http_request(web, method, path, NULL, body, &ans, EMU_REPLY_MS) < 0)
        return -1;
    return ans.status;
}

/* A form POST. */
static int post(const char *path, const char *form)
{
    static const char type[] =
        "Content-Type: application/x-www-form-urlencoded\r\n";

    if (http_request(web, "POST", path, type, form, &ans, EMU_REPLY_MS) < 0)
        return -1;
    return ans.status;
}

static int exists(const char *path)
{
    struct stat st;

    return lstat(path, &st) == 0;
}

/* The state (GET /state.json) until it contains want (or, with
 * absent, no longer contains it): 1, or 0 after STATE_WAIT_MS. */
static int state_until(const char *want, int absent)
{
    double end = emu_now_ms() + STATE_WAIT_MS;

    do {
        if (req("GET", "/state.json", NULL) == 200 &&
            (strstr(ans.body, want) != NULL) != absent)
            return 1;
        emu_sleep_ms(20);
    } while (emu_now_ms() < end);
    fprintf(stderr, "state: %s\nwanted %s%s\n", ans.body, absent ? "no " : "",
            want);
    return 0;
}

/* Entries of the script directory but "." and "..". */
static int dir_entries(void)
{
    struct dirent *de;
    DIR *d = opendir(dir);
    int n = 0;

    if (!d)
        return -1;
    while ((de = readdir(d)) != NULL)
        if (strcmp(de->d_name, ".") != 0 && strcmp(de->d_name, "..") != 0)
            n++;
    closedir(d);
    return n;
}

static void test_files(void)
{
    char v[128];

    CHECK_EQ(req("GET", "/scripts.json", NULL), 200);
    CHECK(strstr(ans.body, "\"scripts\":[]") != NULL);
    CHECK_EQ(req("PUT", "/scripts/ping.lua", ping_lua), 201);
    CHECK_EQ(req("PUT", "/scripts/b-2_x.lua", "-- b\n"), 201);
    CHECK_EQ(req("PUT", "/scripts/b-2_x.lua", "-- b again\n"), 200);
    CHECK_EQ(req("PUT", "/scripts/a.lua", ""), 201);
    CHECK_EQ(req("GET", "/scripts.json", NULL), 200);
    /* Sorted by name, with their sizes. */
    {
        const char *a = strstr(ans.body, "{\"name\":\"a.lua\",\"size\":0,");
        const char *b =
            strstr(ans.body, "{\"name\":\"b-2_x.lua\",\"size\":11,");
        char want[64];
        const char *p;

        snprintf(want, sizeof want, "{\"name\":\"ping.lua\",\"size\":%u,",
                 (unsigned)strlen(ping_lua));
        p = strstr(ans.body, want);
        CHECK(a && b && p && a < b && b < p);
        CHECK(strstr(ans.body, "\"mtime\":") != NULL);
        if (!(a && b && p))
            fprintf(stderr, "list: %s\n", ans.body);
    }
    CHECK_EQ(req("GET", "/scripts/ping.lua", NULL), 200);
    CHECK(strcmp(ans.body, ping_lua) == 0);
    CHECK(http_header(&ans, "Content-Disposition", v, sizeof v) &&
          strcmp(v, "attachment; filename=\"ping.lua\"") == 0);
    CHECK_EQ(req("DELETE", "/scripts/b-2_x.lua", NULL), 200);
    CHECK_EQ(req("GET", "/scripts/b-2_x.lua", NULL), 404);
    CHECK_EQ(req("DELETE", "/scripts/b-2_x.lua", NULL), 404);
    CHECK_EQ(req("DELETE", "/scripts/a.lua", NULL), 200);
    /* ping.lua alone: no temporary file left. */
    CHECK_EQ(dir_entries(), 1);
}

static void test_names(void)
{
    static const char *const bad[] = {
        "/scripts/../x.lua",
        "/scripts/a/b.lua",
        "/scripts/%2e%2e%2fx.lua",
        "/scripts/..%2fx.lua",
        "/scripts/.hidden.lua",
        "/scripts/x.txt",
        "/scripts/x.lua.txt",
        "/scripts/.lua",
        "/scripts/",
        "/scripts/a%20b.lua",
        /* A name over the limit (one literal, split across lines). */
        ("/scripts/"
         "a123456789012345678901234567890123456789012345678901234567890.lua"),
    };
    static const char *const nul[] = {
        "/scripts/ping.lua%00.txt", "/scripts/ping.lua%00",
        "/scripts/ping.lua%0a",     "/scripts/ping.lua%7F",
        "/scripts/ping.lua?x=%00",
    };
    char path[512], link[512], parent_x[512];
    size_t i;
    FILE *f;

    for (i = 0; i < sizeof bad / sizeof bad[0]; i++) {
        CHECK_EQ(req("PUT", bad[i], "print('out')\n"), 400);
        if (ans.status != 400)
            fprintf(stderr, "PUT %s: %d %s\n", bad[i], ans.status, ans.body);
        CHECK(strstr(ans.body, "\"error\":\"") != NULL);
        CHECK_EQ(req("GET", bad[i], NULL), 400);
        CHECK_EQ(req("DELETE", bad[i], NULL), 400);
    }
    /* 64 characters are fine. */
    CHECK_EQ(req("PUT",
                 "/scripts/"
                 "a12345678901234567890123456789012345678901234567890123456789"
                 ".lua",
                 "\n"),
             201);
    CHECK_EQ(req("DELETE",
                 "/scripts/"
                 "a12345678901234567890123456789012345678901234567890123456789"
                 ".lua",
                 NULL),
             200);
    /* A NUL or a control character, percent-encoded: refused whole, not
     * cut at the NUL to a name that exists (ping.lua). */
    for (i = 0; i < sizeof nul / sizeof nul[0]; i++) {
        CHECK_EQ(req("PUT", nul[i], "print('cut')\n"), 400);
        if (ans.status != 400)
            fprintf(stderr, "PUT %s: %d %s\n", nul[i], ans.status, ans.body);
        CHECK_EQ(req("GET", nul[i], NULL), 400);
        CHECK_EQ(req("DELETE", nul[i], NULL), 400);
    }
    CHECK_EQ(req("GET", "/scripts/ping.lua", NULL), 200);
    CHECK(strcmp(ans.body, ping_lua) == 0);
    CHECK_EQ(post("/script/run", "name=ping.lua%00.txt"), 400);
    CHECK_EQ(post("/script/run", "na%00me=ping.lua"), 400);
    CHECK_EQ(post("/script/run?name=ping.lua%00.txt", ""), 400);
    CHECK_EQ(post("/script/run", "name=ping.lua%0A"), 400);
    CHECK_EQ(req("GET", "/script/status", NULL), 200);
    CHECK(strstr(ans.body, "\"running\":false") != NULL);
    snprintf(parent_x, sizeof parent_x, "%s/../x.lua", dir);
    CHECK(!exists(parent_x));
    CHECK(!exists("x.lua"));
    CHECK_EQ(post("/script/run", "name=../x.lua"), 400);
    CHECK_EQ(post("/script/run", "name=nothing.lua"), 404);

    /* A link planted in the directory, to a file outside it. */
    f = fopen(outside, "w");
    REQUIRE(f != NULL);
    fputs("secret\n", f);
    fclose(f);
    snprintf(link, sizeof link, "%s/link.lua", dir);
    REQUIRE(symlink(outside, link) == 0);
    CHECK_EQ(req("GET", "/scripts/link.lua", NULL), 403);
    CHECK(strstr(ans.body, "secret") == NULL);
    CHECK_EQ(req("PUT", "/scripts/link.lua", "print('overwritten')\n"), 403);
    CHECK_EQ(req("DELETE", "/scripts/link.lua", NULL), 403);
    CHECK_EQ(post("/script/run", "name=link.lua"), 403);
    CHECK_EQ(req("GET", "/scripts.json", NULL), 200);
    CHECK(strstr(ans.body, "link.lua") == NULL);
    f = fopen(outside, "r");
    REQUIRE(f != NULL);
    CHECK(fgets(path, sizeof path, f) && strcmp(path, "secret\n") == 0);
    fclose(f);
    CHECK(exists(link));
    unlink(link);
}

/* A request head alone, with a Content-Length: the status the daemon
 * answers before any of the body is sent. */
static int head_only(const char *method, const char *path, size_t length)
{
    char head[512], buf[4096];
    struct sockaddr_in sa;
    size_t got = 0;
    double end = emu_now_ms() + EMU_REPLY_MS;
    int fd, n, status = -1;
    const char *colon = strrchr(web, ':');

    memset(&sa, 0, sizeof sa);
    sa.sin_family = AF_INET;
    sa.sin_port = htons((uint16_t)atoi(colon + 1));
    sa.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    fd = socket(AF_INET, SOCK_STREAM, 0);
    if (fd < 0 || connect(fd, (struct sockaddr *)&sa, sizeof sa) < 0) {
        if (fd >= 0)
            close(fd);
        return -1;
    }
    n = snprintf(head, sizeof head,
                 "%s %s HTTP/1.1\r\nHost: %s\r\nConnection: close\r\n"
                 "Content-Length: %zu\r\n\r\n",
                 method, path, web, length);
    if (send(fd, head, (size_t)n, MSG_NOSIGNAL) != n)
        goto out;
    while (got < sizeof buf - 1 && emu_now_ms() < end) {
        struct timeval tv = {0, 100000};
        ssize_t r;

        setsockopt(fd, SOL_SOCKET, SO_RCVTIMEO, &tv, sizeof tv);
        r = recv(fd, buf + got, sizeof buf - 1 - got, 0);
        if (r == 0)
            break;
        if (r < 0 && (errno == EAGAIN || errno == EWOULDBLOCK)) {
            buf[got] = '\0';
            if (strstr(buf, "\r\n\r\n"))
                break;
            continue;
        }
        if (r < 0)
            break;
        got += (size_t)r;
    }
    buf[got] = '\0';
    if (sscanf(buf, "HTTP/1.%*d %d", &status) != 1)
        status = -1;
out:
    close(fd);
    return status;
}

/* PUT path with the len bytes of body in chunks of 16 KiB: the status,
 * or -1 (no answer). */
static int put_chunked(const char *path, const char *body, size_t len)
{
    size_t cap = len + len / 1024 + 1024, used, off, n;
    char *msg = malloc(cap);
    int r;

    if (!msg)
        return -1;
    used = (size_t)snprintf(msg, cap,
                            "PUT %s HTTP/1.1\r\nHost: %s\r\n"
                            "Connection: close\r\n"
                            "Transfer-Encoding: chunked\r\n\r\n",
                            path, web);
    for (off = 0; off < len; off += n) {
        n = len - off < 16384 ? len - off : 16384;
        used += (size_t)snprintf(msg + used, cap - used, "%zx\r\n", n);
        memcpy(msg + used, body + off, n);
        used += n;
        memcpy(msg + used, "\r\n", 2);
        used += 2;
    }
    used += (size_t)snprintf(msg + used, cap - used, "0\r\n\r\n");
    r = http_exchange(web, msg, used, &ans, EMU_REPLY_MS);
    free(msg);
    return r < 0 ? -1 : ans.status;
}

static void test_caps(void)
{
    char *big = malloc(UPLOAD_MAX + 1);
    char name[512];

    REQUIRE(big != NULL);
    memset(big, '-', UPLOAD_MAX);
    big[UPLOAD_MAX] = '\0';
    CHECK_EQ(req("PUT", "/scripts/big.lua", big), 201);
    CHECK_EQ(req("GET", "/scripts.json", NULL), 200);
    CHECK(strstr(ans.body, "{\"name\":\"big.lua\",\"size\":262144,") != NULL);
    CHECK_EQ(req("DELETE", "/scripts/big.lua", NULL), 200);
    CHECK_EQ(head_only("PUT", "/scripts/big.lua", UPLOAD_MAX + 1), 413);
    snprintf(name, sizeof name, "%s/big.lua", dir);
    CHECK(!exists(name));
    /* The same sizes chunked (no Content-Length to tell): the cap taken,
     * a byte more answered 413 as well, not a reset. */
    CHECK_EQ(put_chunked("/scripts/big.lua", big, UPLOAD_MAX), 201);
    CHECK_EQ(req("DELETE", "/scripts/big.lua", NULL), 200);
    big[UPLOAD_MAX] = '-'; /* a byte more: its NUL no longer */
    CHECK_EQ(put_chunked("/scripts/big.lua", big, UPLOAD_MAX + 1), 413);
    CHECK(strstr(ans.body, "\"error\":\"body larger than 262144 bytes\"") !=
          NULL);
    CHECK(!exists(name));
    free(big);
}

/* A log event with a line containing want within timeout_ms: 1, or 0. */
static int log_until(struct http_stream *s, const char *want, int timeout_ms)
{
    static char data[EV_MAX];
    double end = emu_now_ms() + timeout_ms, left;
    char name[64];
    int r;

    for (;;) {
        left = end - emu_now_ms();
        if (left <= 0)
            return 0;
        r = http_stream_event(s, name, sizeof name, data, sizeof data,
                              (int)left);
        if (r != 1)
            return 0;
        if (strcmp(name, "log") == 0 && strstr(data, want))
            return 1;
    }
}

static void test_run(struct emu *e)
{
    static struct http_stream s;
    struct wsg_client_frame f;
    struct emu_client c;

    REQUIRE(emu_open(&c, e, &emu_tcp) == 0);
    CHECK_EQ(emu_request(&c, ID_PING, NULL, 0, NULL, EMU_REPLY_MS),
             WSG_E_CMD_UNKNOWN);
    /* The log is fed while a stream is open. */
    REQUIRE(http_stream_open(&s, web, "/events", EMU_REPLY_MS) == 0);
    CHECK_EQ(s.status, 200);

    CHECK_EQ(post("/script/run", "name=ping.lua"), 200);
    CHECK(log_until(&s, " script print hello from the web", STATE_WAIT_MS));
    CHECK_EQ(emu_request(&c, ID_PING, NULL, 0, &f, EMU_REPLY_MS),
             WSG_E_SUCCESS);
    CHECK(EMU_NPARAMS(&f) == 4 && memcmp(EMU_PARAMS(&f), "pong", 4) == 0);
    CHECK(state_until("\"script\":{\"name\":\"ping.lua\",\"running\":true,"
                      "\"error\":null}",
                      0));
    CHECK(strstr(ans.body, "\"script_running\"") != NULL);
    CHECK_EQ(req("GET", "/script/status", NULL), 200);
    CHECK(strstr(ans.body, "\"running\":true") != NULL);
    CHECK_EQ(post("/script/run", "name=ping.lua"), 409);

    CHECK_EQ(post("/script/stop", ""), 200);
    CHECK(strstr(ans.body, "\"stopped\":true") != NULL);
    CHECK(state_until("\"script_running\"", 1));
    CHECK(strstr(ans.body, "\"running\":false") != NULL);
    CHECK_EQ(emu_request(&c, ID_PING, NULL, 0, NULL, EMU_REPLY_MS),
             WSG_E_CMD_UNKNOWN);
    CHECK_EQ(post("/script/stop", ""), 200);
    CHECK(strstr(ans.body, "\"stopped\":false") != NULL);

    /* A runtime error: its message and D20 in the state. */
    CHECK_EQ(req("PUT", "/scripts/fail.lua", fail_lua), 201);
    CHECK_EQ(post("/script/run", "name=fail.lua"), 200);
    CHECK(state_until("\"script_running\"", 0));
    CHECK_EQ(emu_send(&c, ID_FAIL, NULL, 0), 0);
    CHECK(state_until("\"script_failure\"", 0));
    CHECK(strstr(ans.body, "\"name\":\"fail.lua\",\"running\":false,"
                           "\"error\":\"") != NULL);
    CHECK(strstr(ans.body, "asked to fail") != NULL);
    CHECK(strstr(ans.body, "\"script_running\"") == NULL);
    CHECK(log_until(&s, "asked to fail", STATE_WAIT_MS));
    CHECK_EQ(req("GET", "/script/status", NULL), 200);
    CHECK(strstr(ans.body, "\"failed\":true") != NULL);
    CHECK(strstr(ans.body, "asked to fail") != NULL);

    /* One that does not compile: 422 with Lua's message, whole (it is
     * the directory's own file); D20. */
    CHECK_EQ(req("PUT", "/scripts/syntax.lua", "this is not lua\n"), 201);
    CHECK_EQ(post("/script/run", "name=syntax.lua"), 422);
    CHECK(strstr(ans.body, "syntax.lua:1: ") != NULL);
    CHECK(strstr(ans.body, "near 'is'") != NULL);
    CHECK(state_until("\"script_failure\"", 0));

    /* The next start clears D20. */
    CHECK_EQ(post("/script/run", "name=ping.lua"), 200);
    CHECK(state_until("\"script_failure\"", 1));
    CHECK_EQ(post("/script/stop", ""), 200);

    http_stream_close(&s);
    emu_close(&c);
}

/* A file outside the script directory: its path, made from name. */
static void outside_file(char *path, size_t cap, const char *name,
                         const char *text)
{
    FILE *f;

    snprintf(path, cap, "%s/%s", top_dir, name);
    f = fopen(path, "w");
    REQUIRE(f != NULL);
    REQUIRE(fputs(text, f) >= 0);
    REQUIRE(fclose(f) == 0);
}

/* What the scripts printed so far (GET /script/output). */
static const char *script_output(void)
{
    return req("GET", "/script/output?from=0", NULL) == 200 ? ans.body : "";
}

/* POST /control runs the control channel's commands, but its `script
 * run` is the page's: a script of the script directory by name, never a
 * file by path (which would run, and show the compile error of, any file
 * the daemon can read). */
static void test_control_run(void)
{
    char marker[512], secret[512], form[700];

    outside_file(marker, sizeof marker, "marker.lua",
                 "print('OUTSIDE-MARKER')\n");
    outside_file(secret, sizeof secret, "secret.lua", "hunter2 s3cr3t\n");
    snprintf(form, sizeof form, "line=script+run+%s", marker);
    CHECK_EQ(post("/control", form), 400);
    CHECK(strstr(ans.body, "\"ok\":false") != NULL);
    CHECK(strstr(ans.body, "NAME.lua") != NULL);
    CHECK(strstr(script_output(), "OUTSIDE-MARKER") == NULL);
    snprintf(form, sizeof form, "line=script+run+%s", secret);
    CHECK_EQ(post("/control", form), 400);
    CHECK(strstr(ans.body, "s3cr3t") == NULL);
    CHECK_EQ(post("/control", "line=script+run+/etc/passwd"), 400);
    CHECK(strstr(ans.body, "root") == NULL);
    CHECK_EQ(post("/control", "line=script+run+../marker.lua"), 400);
    CHECK(strstr(script_output(), "OUTSIDE-MARKER") == NULL);
    CHECK_EQ(req("GET", "/script/status", NULL), 200);
    CHECK(strstr(ans.body, "marker") == NULL &&
          strstr(ans.body, "secret") == NULL);
    /* By name: the directory's script, as POST /script/run runs it. */
    CHECK_EQ(post("/control", "line=script+run+ping.lua"), 200);
    CHECK(strstr(ans.body, "ok script running ping.lua") != NULL);
    CHECK_EQ(post("/control", "line=script+stop"), 200);
    unlink(marker);
    unlink(secret);
}

/* Runs against link swaps: POST /script/run of a name that another
 * process keeps replacing, in turn by a regular file of the directory and
 * by a symbolic link to a script outside it, which would print a marker.
 * The check and the open are one step, so no run may run the file
 * outside: each is the directory's script (200) or refused (403). */
#define RACE_RUNS  3000
#define RACE_SWAPS 20000000L

static void test_race(void)
{
    char outside_lua[512], src[512], name[512], tmpf[512], tmpl[512];
    int ran = 0, refused = 0, other = 0, i, st;
    pid_t pid;

    outside_file(outside_lua, sizeof outside_lua, "race-outside.lua",
                 "print('OUTSIDE-MARKER')\n");
    snprintf(src, sizeof src, "%s/.race-src", dir);
    snprintf(name, sizeof name, "%s/race.lua", dir);
    snprintf(tmpf, sizeof tmpf, "%s/.race-f", dir);
    snprintf(tmpl, sizeof tmpl, "%s/.race-l", dir);
    {
        FILE *f = fopen(src, "w");

        REQUIRE(f && fputs("print('inside')\n", f) >= 0 && fclose(f) == 0);
    }
    REQUIRE(link(src, name) == 0);
    fflush(NULL);
    pid = fork();
    REQUIRE(pid >= 0);
    if (pid == 0) {
        long k;

        /* Bounded: it ends by itself should the parent not stop it. */
        for (k = 0; k < RACE_SWAPS; k++) {
            /* rename() of a second link to the same file does nothing:
             * one left from such a turn goes first. */
            unlink(tmpf);
            if (link(src, tmpf) == 0)
                rename(tmpf, name);
            if (symlink(outside_lua, tmpl) == 0)
                rename(tmpl, name);
        }
        _exit(0);
    }
    for (i = 0; i < RACE_RUNS; i++) {
        st = post("/script/run", "name=race.lua");
        if (st == 200)
            ran++;
        else if (st == 403)
            refused++;
        else
            other++;
    }
    kill(pid, SIGKILL);
    waitpid(pid, NULL, 0);
    printf("race: %d runs, %d refused (a link), %d other\n", ran, refused,
           other);
    /* Both sides of the swap were met, and nothing else happened. */
    CHECK(ran > 0 && refused > 0);
    CHECK_EQ(other, 0);
    CHECK(strstr(script_output(), "OUTSIDE-MARKER") == NULL);
    unlink(name);
    unlink(tmpf);
    unlink(tmpl);
    unlink(src);
    unlink(outside_lua);
}

/* n bytes of a comment, as a script's text. */
static const char *text_of(size_t n)
{
    static char buf[2048];

    memset(buf, '-', n);
    buf[n] = '\0';
    return buf;
}

/* Uploads within the directory's bounds (--script-quota 1000
 * --script-files 3): past the bytes 507 (a script larger than the whole
 * quota 413), past the count 507, a replacement counted for its new size
 * only; what is refused is not written. */
static void test_quota(const char *exe)
{
    const char *args[] = {
        "--tcp", "127.0.0.1:0",    "--web", "127.0.0.1:0",    "--script-dir",
        dir,     "--script-quota", "1000",  "--script-files", "3",
        NULL};
    char path[512];
    struct emu e;

    REQUIRE(emu_start(&e, exe, args) == 0);
    REQUIRE(emu_field(&e, "web", web, sizeof web) != NULL);
    CHECK_EQ(dir_entries(), 0);
    CHECK_EQ(req("PUT", "/scripts/a.lua", text_of(400)), 201);
    CHECK_EQ(req("PUT", "/scripts/b.lua", text_of(400)), 201);
    /* 1100 bytes in all: no room. */
    CHECK_EQ(req("PUT", "/scripts/c.lua", text_of(300)), 507);
    CHECK(strstr(ans.body, "--script-quota") != NULL);
    /* A replacement: its new size in place of its old one. */
    CHECK_EQ(req("PUT", "/scripts/a.lua", text_of(600)), 200);
    CHECK_EQ(req("PUT", "/scripts/a.lua", text_of(601)), 507);
    /* More than the quota on its own. */
    CHECK_EQ(req("PUT", "/scripts/c.lua", text_of(1001)), 413);
    CHECK_EQ(req("PUT", "/scripts/c.lua", "-"), 507);
    CHECK_EQ(dir_entries(), 2);
    /* Room again; then the count is the bound. */
    CHECK_EQ(req("DELETE", "/scripts/b.lua", NULL), 200);
    CHECK_EQ(req("PUT", "/scripts/c.lua", text_of(100)), 201);
    CHECK_EQ(req("PUT", "/scripts/d.lua", text_of(10)), 201);
    CHECK_EQ(req("PUT", "/scripts/e.lua", "-"), 507);
    CHECK(strstr(ans.body, "--script-files") != NULL);
    CHECK_EQ(req("PUT", "/scripts/d.lua", text_of(20)), 200);
    CHECK_EQ(dir_entries(), 3);
    snprintf(path, sizeof path, "%s/e.lua", dir);
    CHECK(!exists(path));
    CHECK_EQ(emu_stop(&e), 0);
    snprintf(path, sizeof path, "%s/a.lua", dir);
    unlink(path);
    snprintf(path, sizeof path, "%s/c.lua", dir);
    unlink(path);
    snprintf(path, sizeof path, "%s/d.lua", dir);
    unlink(path);
}

/* A script whose error is as long as the host keeps, made of what JSON
 * escapes longest (control characters, 6 bytes each) and ending in a
 * two-byte character the host's cut may split: the run's 422 and GET
 * /script/status are still answered, each in valid JSON (UTF-8). */
static void test_long_error(void)
{
    static const char long_lua[] =
        "error(string.rep('\\1', 400) .. string.rep('\\195\\169', 100), 0)\n";

    CHECK_EQ(req("PUT", "/scripts/long.lua", long_lua), 201);
    CHECK_EQ(post("/script/run", "name=long.lua"), 422);
    CHECK(http_json_valid(ans.body, ans.body_len));
    CHECK(strstr(ans.body, "\\u0001\\u0001") != NULL);
    CHECK_EQ(req("GET", "/script/status", NULL), 200);
    CHECK(http_json_valid(ans.body, ans.body_len));
    if (!http_json_valid(ans.body, ans.body_len))
        fprintf(stderr, "status: %s\n", ans.body);
    CHECK(strstr(ans.body, "\"failed\":true") != NULL);
    CHECK(strstr(ans.body, "\"error\":\"\\u0001\\u0001") != NULL);
    CHECK(strstr(ans.body, "\\u0001\xc3\xa9") != NULL);
    CHECK(strstr(ans.body, "\"memory_max\":") != NULL);
    CHECK_EQ(req("DELETE", "/scripts/long.lua", NULL), 200);
}

/* A daemon without --script-dir: every endpoint says what is missing. */
static void test_no_dir(const char *exe)
{
    static const char *const args[] = {"--tcp", "127.0.0.1:0", "--web",
                                       "127.0.0.1:0", NULL};
    struct emu e;

    REQUIRE(emu_start(&e, exe, args) == 0);
    REQUIRE(emu_field(&e, "web", web, sizeof web) != NULL);
    CHECK_EQ(req("GET", "/scripts.json", NULL), 409);
    CHECK(strstr(ans.body, "--script-dir DIR") != NULL);
    CHECK_EQ(req("PUT", "/scripts/a.lua", "print(1)\n"), 409);
    CHECK(strstr(ans.body, "--script-dir DIR") != NULL);
    CHECK_EQ(req("GET", "/scripts/a.lua", NULL), 409);
    CHECK_EQ(req("DELETE", "/scripts/a.lua", NULL), 409);
    CHECK_EQ(post("/script/run", "name=a.lua"), 409);
    CHECK(strstr(ans.body, "--script-dir DIR") != NULL);
    /* A bad name is the client's error still. */
    CHECK_EQ(req("PUT", "/scripts/x.txt", "print(1)\n"), 400);
    CHECK_EQ(emu_stop(&e), 0);
}

int main(int argc, char **argv)
{
    const char *exe = emu_exe(argc, argv);
    const char *args[] = {"--tcp",       "127.0.0.1:0",  "--web",
                          "127.0.0.1:0", "--script-dir", dir,
                          NULL};
    char top[] = "/tmp/wsgemu-webscripts.XXXXXX", path[512];
    struct emu e;

    if (!WSG_TEST_HAVE_WEB)
        test_skip("wsgemu was built without libmicrohttpd");
    REQUIRE(mkdtemp(top) != NULL);
    snprintf(top_dir, sizeof top_dir, "%s", top);
    snprintf(dir, sizeof dir, "%s/user", top);
    snprintf(outside, sizeof outside, "%s/outside.lua", top);
    REQUIRE(mkdir(dir, 0755) == 0);

    REQUIRE(emu_start(&e, exe, args) == 0);
    REQUIRE(emu_field(&e, "web", web, sizeof web) != NULL);
    test_files();
    test_names();
    test_caps();
    test_run(&e);
    test_control_run();
    test_race();
    test_long_error();
    CHECK_EQ(emu_stop(&e), 0);
    /* Only what the test made. */
    snprintf(path, sizeof path, "%s/ping.lua", dir);
    unlink(path);
    snprintf(path, sizeof path, "%s/fail.lua", dir);
    unlink(path);
    snprintf(path, sizeof path, "%s/syntax.lua", dir);
    unlink(path);
    test_quota(exe);
    test_no_dir(exe);

    unlink(outside);
    CHECK_EQ(rmdir(dir), 0);
    CHECK_EQ(rmdir(top), 0);
    TEST_EXIT();
}
