/*
 * The web page's Host and Origin rules (src/daemon/web_host.c), without a
 * server: which Host values name the page (loopback names, the address it
 * listens on, --web-host's list), read exactly; which names --web-host
 * takes; which Origin a change is taken from. integ_webhost asks the
 * daemon the same over HTTP.
 */
#include <string.h>

#include "check.h"
#include "web_host.h"

static const uint8_t any[4] = {0, 0, 0, 0};
static const uint8_t lan[4] = {192, 168, 1, 20};

static int allowed(const char *host, const char *allow, const uint8_t *bound)
{
    return wsg_web_host_allowed(host, allow, bound);
}

static int name_ok(const char *name)
{
    return wsg_web_host_name_valid(name, strlen(name)) == 0;
}

static void test_split(void)
{
    const char *h;
    size_t n;
    unsigned p;

    CHECK_EQ(wsg_web_host_split("localhost:8080", 14, &h, &n, &p), 0);
    CHECK(n == 9 && memcmp(h, "localhost", 9) == 0 && p == 8080);
    CHECK_EQ(wsg_web_host_split("[::1]:1", 7, &h, &n, &p), 0);
    CHECK(n == 5 && p == 1);
    CHECK_EQ(wsg_web_host_split("example", 7, &h, &n, &p), 0);
    CHECK(n == 7 && p == 0);
    /* Only the length given is read: the rest is not the value's. */
    CHECK_EQ(wsg_web_host_split("a:80x", 4, &h, &n, &p), 0);
    CHECK(n == 1 && p == 80);
    CHECK(wsg_web_host_split("", 0, &h, &n, &p) < 0);
    CHECK(wsg_web_host_split(":80", 3, &h, &n, &p) < 0);
    CHECK(wsg_web_host_split("a:", 2, &h, &n, &p) < 0);
    CHECK(wsg_web_host_split("a:0", 3, &h, &n, &p) < 0);
    CHECK(wsg_web_host_split("a:65536", 7, &h, &n, &p) < 0);
    CHECK(wsg_web_host_split("a:000080", 8, &h, &n, &p) < 0);
    CHECK(wsg_web_host_split("a:-1", 4, &h, &n, &p) < 0);
    CHECK(wsg_web_host_split("a:1:2", 5, &h, &n, &p) < 0);
    CHECK(wsg_web_host_split("[::1]x", 6, &h, &n, &p) < 0);
    CHECK(wsg_web_host_split("[::1", 4, &h, &n, &p) < 0);
}

static void test_ipv4(void)
{
    uint8_t a[4];

    CHECK(wsg_web_host_ipv4("127.0.0.1", 9, a) == 0 && a[0] == 127 &&
          a[3] == 1);
    CHECK(wsg_web_host_ipv4("255.255.255.255", 15, a) == 0 && a[2] == 255);
    CHECK(wsg_web_host_ipv4("0.0.0.0", 7, a) == 0);
    CHECK(wsg_web_host_ipv4("127.0.0.256", 11, a) < 0);
    CHECK(wsg_web_host_ipv4("127.0.0", 7, a) < 0);
    CHECK(wsg_web_host_ipv4("127.1", 5, a) < 0);
    CHECK(wsg_web_host_ipv4("127.0.0.1.", 10, a) < 0);
    CHECK(wsg_web_host_ipv4("127.0.0.01", 10, a) < 0);
    CHECK(wsg_web_host_ipv4("0177.0.0.1", 10, a) < 0);
    CHECK(wsg_web_host_ipv4("0x7f.0.0.1", 10, a) < 0);
    CHECK(wsg_web_host_ipv4("1270.0.0.1", 10, a) < 0);
    CHECK(wsg_web_host_ipv4("127..0.1", 8, a) < 0);
    CHECK(wsg_web_host_ipv4("+127.0.0.1", 10, a) < 0);
    CHECK(wsg_web_host_ipv4("", 0, a) < 0);
}

static void test_hosts(void)
{
    static const char *const bad[] = {"127.attacker.example",
                                      "127.0.0.1.nip.io",
                                      "localhost.evil",
                                      "localhost.",
                                      "[::1]x",
                                      "127.0.0.256",
                                      "0x7f.1",
                                      "127.1",
                                      "",
                                      "localhost:0",
                                      "localhost:65536",
                                      "[::ffff:127.0.0.1]",
                                      "127.0.0.1 ",
                                      "user@localhost",
                                      "0.0.0.0",
                                      "192.168.1.20"};
    static const char *const good[] = {
        "localhost",        "LOCALHOST:1", "127.0.0.1", "127.0.0.1:65535",
        "127.200.3.4:8080", "[::1]",       "[::1]:80"};
    size_t i;

    for (i = 0; i < sizeof bad / sizeof bad[0]; i++) {
        CHECK(!allowed(bad[i], NULL, any));
        CHECK(!allowed(bad[i], "", any));
    }
    for (i = 0; i < sizeof good / sizeof good[0]; i++)
        CHECK(allowed(good[i], NULL, any));
    CHECK(!allowed(NULL, "a.example", any));
    /* The address it listens on, when it is one. */
    CHECK(allowed("192.168.1.20", NULL, lan));
    CHECK(allowed("192.168.1.20:80", NULL, lan));
    CHECK(!allowed("192.168.1.2", NULL, lan));
    CHECK(!allowed("192.168.1.200", NULL, lan));
    CHECK(allowed("localhost", NULL, lan));
    /* The list: whole names, any case, any port. */
    CHECK(allowed("gripper.lab", "gripper.lab,10.0.0.9", any));
    CHECK(allowed("Gripper.LAB:8080", "gripper.lab,10.0.0.9", any));
    CHECK(allowed("10.0.0.9:80", "gripper.lab,10.0.0.9", any));
    CHECK(allowed("[fe80::1]:80", "[fe80::1]", any));
    CHECK(!allowed("gripper.la", "gripper.lab,10.0.0.9", any));
    CHECK(!allowed("gripper.lab.evil", "gripper.lab,10.0.0.9", any));
    CHECK(!allowed("x.gripper.lab", "gripper.lab,10.0.0.9", any));
    CHECK(!allowed("lab", "gripper.lab,10.0.0.9", any));
    CHECK(!allowed("10.0.0.90", "gripper.lab,10.0.0.9", any));
    CHECK(!allowed("gripper.lab,10.0.0.9", "gripper.lab,10.0.0.9", any));
    CHECK(!allowed("", "gripper.lab,", any));
}

static void test_names(void)
{
    CHECK(name_ok("gripper"));
    CHECK(name_ok("gripper.lab.example"));
    CHECK(name_ok("Cell-4.example"));
    CHECK(name_ok("10.0.0.9"));
    CHECK(name_ok("[fe80::1]"));
    CHECK(name_ok("[::ffff:10.0.0.9]"));
    CHECK(!name_ok(""));
    CHECK(!name_ok("*"));
    CHECK(!name_ok("*.example"));
    CHECK(!name_ok("gripper:80"));
    CHECK(!name_ok("gripper."));
    CHECK(!name_ok(".gripper"));
    CHECK(!name_ok("a..b"));
    CHECK(!name_ok("-a.example"));
    CHECK(!name_ok("a-.example"));
    CHECK(!name_ok("a_b.example"));
    CHECK(!name_ok("a b"));
    CHECK(!name_ok("256.1.1.1"));
    CHECK(!name_ok("1.2.3"));
    CHECK(!name_ok("[::1"));
    CHECK(!name_ok("[zz::1]"));
    CHECK(!name_ok("[]"));
    CHECK(!name_ok("http://a"));
    CHECK(!name_ok("0123456789012345678901234567890123456789012345678901234"
                   "567890123.example")); /* a label of 64 */
    CHECK(name_ok("012345678901234567890123456789012345678901234567890123"
                  "456789012.example")); /* of 63 */
}

static void test_origins(void)
{
    const char *allow = "gripper.lab";

    CHECK(wsg_web_origin_allowed(NULL, "localhost", NULL, any));
    CHECK(wsg_web_origin_allowed("http://localhost:8080", "localhost:8080",
                                 NULL, any));
    CHECK(wsg_web_origin_allowed("http://LocalHost:8080", "localhost:8080",
                                 NULL, any));
    CHECK(
        wsg_web_origin_allowed("http://localhost", "localhost:80", NULL, any));
    CHECK(wsg_web_origin_allowed("http://gripper.lab:8080", "gripper.lab:8080",
                                 allow, any));
    /* Equal to the Host is not enough: the name must be the page's. */
    CHECK(!wsg_web_origin_allowed("http://attacker.example",
                                  "attacker.example", NULL, any));
    CHECK(!wsg_web_origin_allowed("http://127.0.0.1.nip.io:80",
                                  "127.0.0.1.nip.io:80", NULL, any));
    /* The page's names, but another origin than this request's Host. */
    CHECK(!wsg_web_origin_allowed("http://localhost:8080", "127.0.0.1:8080",
                                  NULL, any));
    CHECK(!wsg_web_origin_allowed("http://localhost:8081", "localhost:8080",
                                  NULL, any));
    CHECK(!wsg_web_origin_allowed("http://gripper.lab:8080", "localhost:8080",
                                  allow, any));
    CHECK(!wsg_web_origin_allowed("https://localhost:8080", "localhost:8080",
                                  NULL, any));
    CHECK(!wsg_web_origin_allowed("null", "localhost:8080", NULL, any));
    CHECK(!wsg_web_origin_allowed("http://localhost:8080/", "localhost:8080",
                                  NULL, any));
    CHECK(!wsg_web_origin_allowed("http://localhost:8080", NULL, NULL, any));
    CHECK(!wsg_web_origin_allowed("", "localhost:8080", NULL, any));
}

int main(void)
{
    test_split();
    test_ipv4();
    test_hosts();
    test_names();
    test_origins();
    TEST_EXIT();
}
