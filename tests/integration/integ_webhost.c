/*
 * integ_webhost: the names the web page answers to, against DNS
 * rebinding (a site that points its own name at the gripper's address),
 * and the pages that may change something through it.
 *
 * - on loopback: a Host that only looks like a loopback name is refused
 *   with 421 and a body that says why (127.attacker.example,
 *   127.0.0.1.nip.io, localhost.evil, [::1]x, 127.0.0.256, 0x7f.1, 127.1,
 *   0177.0.0.1, a port of 0, of 65536 or with a letter, an empty Host, a
 *   request without one (HTTP/1.0)), for a change too (POST /stop does
 *   nothing); localhost, 127.x.y.z and [::1], with a port or without, in
 *   any case, are answered;
 * - a change (POST) with an Origin is taken only from the page itself:
 *   http:// and the request's own Host; another site, another loopback
 *   name than the Host's, https, "null" are refused with 403;
 * - listening on 0.0.0.0 (a random port) it refuses foreign names all the
 *   same, and the rebinding request (Host and Origin both the attacker's)
 *   with them; 0.0.0.0 itself is no name;
 * - listening on one non-loopback address of this machine, that address
 *   is answered too (skipped where the machine has none);
 * - --web-host (repeated, comma-separated, and the config file's
 *   web-host, all adding up) admits exactly the names it lists, in any
 *   case, with any port: not a name they end with, start with or are a
 *   part of; an Origin of one listed name is refused on a request to
 *   another; a bad name (with a port, a wildcard, empty) stops the
 *   daemon with status 2.
 *
 * Built without libmicrohttpd (WSG_TEST_HAVE_WEB 0) it is skipped.
 */
#define _GNU_SOURCE

#include "check.h"
#include "emu.h"
#include "emu_http.h"

#include <arpa/inet.h>
#include <ifaddrs.h>
#include <netinet/in.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#ifndef WSG_TEST_HAVE_WEB
#define WSG_TEST_HAVE_WEB 0
#endif

static const char *exe;
static char web[64];     /* where to connect: 127.0.0.1:PORT or ADDR:PORT */
static const char *port; /* ":PORT" of web */
static struct http_answer ans;

/* GET /state.json with the Host header host. */
static int get_host(const char *host)
{
    char hdr[320];

    snprintf(hdr, sizeof hdr, "Host: %s\r\n", host);
    if (http_request(web, "GET", "/state.json", hdr, NULL, &ans,
                     EMU_REPLY_MS) < 0)
        return -1;
    return ans.status;
}

/* The same with host followed by the server's own port. */
static int get_host_port(const char *host)
{
    char h[256];

    snprintf(h, sizeof h, "%s%s", host, port);
    return get_host(h);
}

/* POST path (harmless: /ack with nothing to acknowledge) with Host host
 * and Origin origin (NULL: none). */
static int post(const char *path, const char *host, const char *origin)
{
    char hdr[512];
    int n;

    n = snprintf(hdr, sizeof hdr, "Host: %s\r\n", host);
    if (origin)
        snprintf(hdr + n, sizeof hdr - (size_t)n, "Origin: %s\r\n", origin);
    if (http_request(web, "POST", path, hdr, NULL, &ans, EMU_REPLY_MS) < 0)
        return -1;
    return ans.status;
}

/* A refusal of the Host says what it answers to. */
static void check_refused(const char *host)
{
    int st = get_host(host);

    CHECK_EQ(st, 421);
    if (st != 421)
        fprintf(stderr, "Host '%s' was answered %d\n", host, st);
    else
        CHECK(strstr(ans.body, "\"error\":\"Host is not a name of this "
                               "server") != NULL &&
              strstr(ans.body, "--web-host") != NULL);
}

static void check_answered(const char *host)
{
    int st = get_host(host);

    CHECK_EQ(st, 200);
    if (st != 200)
        fprintf(stderr, "Host '%s' was answered %d: %s\n", host, st, ans.body);
    else
        CHECK(strncmp(ans.body, "{\"width\":", 9) == 0);
}

/* Start a daemon with args and take the port its page listens on; the
 * page is reached at connect_ip. */
static void start(struct emu *e, const char *const *args,
                  const char *connect_ip)
{
    char field[64];
    const char *colon;

    REQUIRE(emu_start(e, exe, args) == 0);
    REQUIRE(emu_field(e, "web", field, sizeof field) != NULL);
    colon = strrchr(field, ':');
    REQUIRE(colon != NULL);
    snprintf(web, sizeof web, "%s%s", connect_ip, colon);
    port = strrchr(web, ':');
}

/* Names that are none of the page's, though they look like loopback. */
static void check_lookalikes(void)
{
    static const char *const bad[] = {
        "127.attacker.example",
        "127.0.0.1.nip.io",
        "localhost.evil",
        "localhost.",
        "[::1]x",
        "[::1",
        "127.0.0.256",
        "0x7f.1",
        "0x7f000001",
        "2130706433",
        "127.1",
        "0177.0.0.1",
        "127.0.0.01",
        "127.0.0.1. evil",
        "127.0.0.1 .evil",
        "[::ffff:127.0.0.1]",
        "[0:0:0:0:0:0:0:1]",
        "user@localhost",
        "localhost:0",
        "localhost:65536",
        "localhost:80x",
        "localhost:",
        "localhost:+80",
        "127.0.0.1:1:2",
        "attacker.example",
        "",
    };
    size_t i;

    for (i = 0; i < sizeof bad / sizeof bad[0]; i++)
        check_refused(bad[i]);
    /* The same with the server's port after them. */
    CHECK_EQ(get_host_port("127.attacker.example"), 421);
    CHECK_EQ(get_host_port("127.0.0.1.nip.io"), 421);
    CHECK_EQ(get_host_port("localhost.evil"), 421);
    CHECK_EQ(get_host_port("attacker.example"), 421);
}

static void check_loopback_names(void)
{
    check_answered("localhost");
    check_answered("127.0.0.1");
    check_answered("[::1]");
    CHECK_EQ(get_host_port("localhost"), 200);
    CHECK_EQ(get_host_port("LocalHost"), 200);
    CHECK_EQ(get_host_port("127.0.0.1"), 200);
    CHECK_EQ(get_host_port("127.1.2.3"), 200);
    CHECK_EQ(get_host_port("[::1]"), 200);
    check_answered("127.255.255.255:65535");
    check_answered("localhost:1");
}

/* A part of a loopback server's test: the rest of the Host rules. */
static void test_loopback(void)
{
    static const char *const args[] = {"--tcp", "127.0.0.1:0", "--web",
                                       "127.0.0.1:0", NULL};
    char req[128], h[96], o[128];
    struct emu e;

    start(&e, args, "127.0.0.1");
    check_lookalikes();
    check_loopback_names();

    /* HTTP/1.0 without a Host: no name, refused (a browser always sends
     * one); with one, answered. */
    REQUIRE(http_request_raw(web, "GET /state.json HTTP/1.0\r\n\r\n", &ans,
                             EMU_REPLY_MS) == 0);
    CHECK_EQ(ans.status, 421);
    CHECK(strstr(ans.body, "--web-host") != NULL);
    snprintf(req, sizeof req,
             "GET /state.json HTTP/1.0\r\nHost: 127.0.0.1%s\r\n\r\n", port);
    REQUIRE(http_request_raw(web, req, &ans, EMU_REPLY_MS) == 0);
    CHECK_EQ(ans.status, 200);

    /* A change under a foreign Host does nothing: refused first. */
    CHECK_EQ(post("/stop", "127.attacker.example", NULL), 421);
    CHECK_EQ(post("/stop", "attacker.example", "http://attacker.example"),
             421);

    /* Origin: the page's own only. */
    snprintf(h, sizeof h, "127.0.0.1%s", port);
    snprintf(o, sizeof o, "http://127.0.0.1%s", port);
    CHECK_EQ(post("/ack", h, o), 200);
    CHECK_EQ(post("/ack", h, NULL), 200); /* no browser: no Origin */
    CHECK_EQ(post("/ack", h, "http://elsewhere.example"), 403);
    CHECK(strstr(ans.body, "foreign origin") != NULL);
    snprintf(o, sizeof o, "http://127.0.0.1.nip.io%s", port);
    CHECK_EQ(post("/ack", h, o), 403);
    /* Another loopback name, or another port: another origin. */
    snprintf(o, sizeof o, "http://localhost%s", port);
    CHECK_EQ(post("/ack", h, o), 403);
    CHECK_EQ(post("/ack", h, "http://127.0.0.1:1"), 403);
    snprintf(o, sizeof o, "https://127.0.0.1%s", port);
    CHECK_EQ(post("/ack", h, o), 403);
    CHECK_EQ(post("/ack", h, "null"), 403);
    snprintf(o, sizeof o, "http://127.0.0.1%s/", port);
    CHECK_EQ(post("/ack", h, o), 403);
    snprintf(h, sizeof h, "localhost%s", port);
    snprintf(o, sizeof o, "http://LOCALHOST%s", port);
    CHECK_EQ(post("/ack", h, o), 200);
    /* Port 80 is the same left out or given. */
    CHECK_EQ(post("/ack", "localhost", "http://localhost:80"), 200);
    CHECK_EQ(post("/ack", "localhost:80", "http://localhost"), 200);

    CHECK_EQ(emu_stop(&e), 0);
}

/* 0.0.0.0: every address, and still only the page's names. */
static void test_any_address(void)
{
    static const char *const args[] = {"--tcp", "127.0.0.1:0", "--web",
                                       "0.0.0.0:0", NULL};
    struct emu e;

    start(&e, args, "127.0.0.1");
    check_lookalikes();
    check_loopback_names();
    check_refused("0.0.0.0");
    CHECK_EQ(get_host_port("0.0.0.0"), 421);
    CHECK_EQ(post("/stop", "attacker.example", "http://attacker.example"),
             421);
    CHECK_EQ(emu_stop(&e), 0);
}

/* One address of this machine that is not loopback, or 0. */
static int other_address(char *buf, size_t cap)
{
    struct ifaddrs *ifs, *i;
    int found = 0;

    if (getifaddrs(&ifs) < 0)
        return 0;
    for (i = ifs; i && !found; i = i->ifa_next) {
        const struct sockaddr_in *sa = (const void *)i->ifa_addr;

        if (!sa || sa->sin_family != AF_INET ||
            (ntohl(sa->sin_addr.s_addr) >> 24) == 127)
            continue;
        found = inet_ntop(AF_INET, &sa->sin_addr, buf, (socklen_t)cap) != NULL;
    }
    freeifaddrs(ifs);
    return found;
}

static void test_own_address(void)
{
    char addr[INET_ADDRSTRLEN], ep[64];
    const char *args[] = {"--tcp", "127.0.0.1:0", "--web", ep, NULL};
    struct emu e;

    if (!other_address(addr, sizeof addr)) {
        printf("no address but loopback here: its part skipped\n");
        return;
    }
    snprintf(ep, sizeof ep, "%s:0", addr);
    start(&e, args, addr);
    CHECK_EQ(get_host_port(addr), 200);
    check_answered(addr);
    CHECK_EQ(get_host_port("localhost"), 200);
    CHECK_EQ(get_host_port("attacker.example"), 421);
    CHECK_EQ(emu_stop(&e), 0);
}

/* --web-host and the config file's web-host. */
static void test_allow_list(void)
{
    char path[256], h[128], o[128];
    const char *args[] = {"--tcp",      "127.0.0.1:0",
                          "--web",      "127.0.0.1:0",
                          "--config",   path,
                          "--web-host", "gripper.lab.example, Other.Example",
                          "--web-host", "10.1.2.3",
                          NULL};
    static const char *const bad[] = {"gripper.lab.example.evil",
                                      "lab.example",
                                      "x.gripper.lab.example",
                                      "gripper.lab.exampl",
                                      "gripper-lab.example",
                                      "gripper.lab.example.",
                                      "other.example.com",
                                      "10.1.2.4",
                                      "10.1.2.3.nip.io",
                                      "cfg.example.org",
                                      "example"};
    struct emu e;
    size_t i;

    emu_temp_file(path, sizeof path, "webhost", "web-host = cfg.example\n");
    start(&e, args, "127.0.0.1");
    check_answered("gripper.lab.example");
    CHECK_EQ(get_host_port("gripper.lab.example"), 200);
    CHECK_EQ(get_host_port("GRIPPER.Lab.Example"), 200);
    check_answered("other.example:8080");
    check_answered("10.1.2.3");
    CHECK_EQ(get_host_port("10.1.2.3"), 200);
    check_answered("cfg.example"); /* the file's, with the command line's */
    for (i = 0; i < sizeof bad / sizeof bad[0]; i++) {
        check_refused(bad[i]);
        CHECK_EQ(get_host_port(bad[i]), 421);
    }
    /* Loopback names stay. */
    check_loopback_names();
    /* A listed name's own origin is taken; another's is not. */
    snprintf(h, sizeof h, "gripper.lab.example%s", port);
    snprintf(o, sizeof o, "http://gripper.lab.example%s", port);
    CHECK_EQ(post("/ack", h, o), 200);
    snprintf(o, sizeof o, "http://other.example%s", port);
    CHECK_EQ(post("/ack", h, o), 403);
    snprintf(o, sizeof o, "http://gripper.lab.example.evil%s", port);
    CHECK_EQ(post("/ack", h, o), 403);
    CHECK_EQ(emu_stop(&e), 0);
    remove(path);
}

static void test_bad_names(void)
{
    static const char *const bad[] = {
        "gripper.lab:8080", "*",           "",          "a,,b",
        "-x.example",       "x_y.example", "256.1.2.3", "http://gripper.lab",
        "[zz::1]"};
    char out[1024], err[2048];
    size_t i;

    for (i = 0; i < sizeof bad / sizeof bad[0]; i++) {
        const char *args[] = {"--web", "127.0.0.1:0", "--web-host", bad[i],
                              NULL};

        CHECK_EQ(
            emu_run(exe, args, EMU_READY_MS, out, sizeof out, err, sizeof err),
            2);
        CHECK(strstr(err, "--web-host") != NULL);
    }
}

int main(int argc, char **argv)
{
    exe = emu_exe(argc, argv);
    if (!WSG_TEST_HAVE_WEB)
        test_skip("wsgemu was built without libmicrohttpd");
    test_loopback();
    test_any_address();
    test_own_address();
    test_allow_list();
    test_bad_names();
    TEST_EXIT();
}
