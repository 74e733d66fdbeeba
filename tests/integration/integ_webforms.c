/*
 * integ_webforms: the web page's settings and motion against the real
 * daemon (--web).
 *
 * - GET /settings.json names the config file and every setting; each
 *   setting POSTed is read back, and the wire shows it (31h, 33h);
 * - a bad value is refused (400) in the command line's words, and a POST
 *   with one bad field changes nothing;
 * - settings change behaviour on the wire at once: CRC off answers a
 *   packet with a wrong checksum, error state on disconnect off leaves no
 *   FAST STOP after a close without 07h, the text interface makes the
 *   next TCP connection speak GCL;
 * - the startup script: a path with a line break (in a directory's name)
 *   is refused and nothing of it is saved to the config file; it is
 *   checked as the start opens it, with one message for a missing path, a
 *   directory, a FIFO and a link alike;
 * - save=1 rewrites the config file (comments kept, lines replaced in
 *   place, missing keys appended) and a daemon started with it has the
 *   values; without --config, save=1 is refused and nothing changes;
 *   a config file that is a symbolic link or read-only is refused (409)
 *   and left as it was; a saved file keeps its mode and owner;
 * - POST /motion: a move before homing is E_NOT_INITIALIZED (409); home,
 *   move, jog, grasp (with its force limit), release and stop move the
 *   gripper as 43h and 41h show;
 * - POST /motion.json moves (sender_id 1221) and configures (1355);
 *   POST /graspconf.json sets the tolerance and clamping travel.
 *
 * Built without libmicrohttpd (WSG_TEST_HAVE_WEB 0) it is skipped.
 */
#define _POSIX_C_SOURCE 200809L

#include "check.h"
#include "emu.h"
#include "emu_ctl.h"
#include "emu_http.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#ifndef WSG_TEST_HAVE_WEB
#define WSG_TEST_HAVE_WEB 0
#endif

static const char *exe;
static char web[64]; /* the web= field of the daemon under test */
static struct http_answer ans;

static int post(const char *path, const char *body)
{
    if (http_request(web, "POST", path,
                     "Content-Type: application/x-www-form-urlencoded\r\n",
                     body, &ans, EMU_REPLY_MS) < 0)
        return -1;
    return ans.status;
}

static int get_settings(void)
{
    if (http_request(web, "GET", "/settings.json", NULL, NULL, &ans,
                     EMU_REPLY_MS) < 0)
        return -1;
    return ans.status;
}

/* The "value" of setting name in a settings answer: a number, or 1/0 for
 * true/false; -1e9 when absent. */
static double setting(const char *json, const char *name)
{
    char key[64];
    const char *p, *v;

    snprintf(key, sizeof key, "\"name\":\"%s\"", name);
    p = strstr(json, key);
    if (!p || !(v = strstr(p, "\"value\":")))
        return -1e9;
    v += 8;
    if (strncmp(v, "true", 4) == 0)
        return 1;
    if (strncmp(v, "false", 5) == 0)
        return 0;
    return strtod(v, NULL);
}

/* The fingers come to rest with the width within lo..hi. */
static void wait_settled(struct emu_client *c, float lo, float hi)
{
    CHECK_EQ(emu_wait_float(c, WSG_CMD_GET_WIDTH, lo, hi, EMU_MOVE_MS, NULL),
             0);
    CHECK_EQ(emu_wait_flags(c, WSG_SF_MOVING, 0, EMU_MOVE_MS, NULL), 0);
}

static float get_float(struct emu_client *c, uint8_t id)
{
    float v = -1.0f;

    CHECK_EQ(emu_get_float(c, id, &v), 0);
    return v;
}

static void start(struct emu *e, const char *config)
{
    const char *args[] = {"--tcp",       "127.0.0.1:0", "--control",
                          "127.0.0.1:0", "--web",       "127.0.0.1:0",
                          NULL,          NULL,          NULL};

    if (config) {
        args[6] = "--config";
        args[7] = config;
    }
    REQUIRE(emu_start(e, exe, args) == 0);
    REQUIRE(emu_field(e, "web", web, sizeof web) != NULL);
}

/* Each setting applied, read back, and seen on the wire. */
static void test_read_back(struct emu_client *c, const char *config)
{
    CHECK_EQ(get_settings(), 200);
    CHECK(strstr(ans.body, config) != NULL);
    CHECK_NEAR(setting(ans.body, "acceleration"), 200.0, 1e-9);
    CHECK_EQ((int)setting(ans.body, "crc"), 1);

    CHECK_EQ(post("/settings.json",
                  "acceleration=250&force-limit=25&clamping-travel=4&"
                  "width-tolerance=3&disconnect-fast-stop=on&crc=on&"
                  "text-interface=off"),
             200);
    CHECK(strstr(ans.body, "\"message\":\"applied (not saved)\"") != NULL);
    CHECK_EQ(get_settings(), 200);
    CHECK_NEAR(setting(ans.body, "acceleration"), 250.0, 1e-9);
    CHECK_NEAR(setting(ans.body, "force-limit"), 25.0, 1e-9);
    CHECK_NEAR(setting(ans.body, "clamping-travel"), 4.0, 1e-9);
    CHECK_NEAR(setting(ans.body, "width-tolerance"), 3.0, 1e-9);
    CHECK_EQ((int)setting(ans.body, "disconnect-fast-stop"), 1);
    CHECK_EQ((int)setting(ans.body, "text-interface"), 0);
    /* As 30h and 32h would: the current values too. */
    CHECK_NEAR(get_float(c, WSG_CMD_GET_ACCELERATION), 250.0, 1e-3);
    CHECK_NEAR(get_float(c, WSG_CMD_GET_FORCE_LIMIT), 25.0, 1e-3);
}

static void test_refused(struct emu_client *c)
{
    CHECK_EQ(post("/settings.json", "acceleration=6000"), 400);
    CHECK(strstr(ans.body, "acceleration: 6000 mm/s^2 is out of range: "
                           "100..5000 mm/s^2") != NULL);
    CHECK_EQ(post("/settings.json", "crc=maybe"), 400);
    CHECK(strstr(ans.body, "crc: 'maybe' is not on or off") != NULL);
    CHECK_EQ(post("/settings.json", "speed=3"), 400);
    CHECK(strstr(ans.body, "unknown setting 'speed'") != NULL);
    CHECK_EQ(post("/settings.json", "script=/nonexistent/x.lua"), 400);
    CHECK(strstr(ans.body, "script: cannot read") != NULL);
    /* All or nothing: the good field before the bad one is not taken. */
    CHECK_EQ(post("/settings.json", "acceleration=300&force-limit=999"), 400);
    CHECK(strstr(ans.body, "force-limit: 999 N is out of range: 5..80 N") !=
          NULL);
    CHECK_EQ(get_settings(), 200);
    CHECK_NEAR(setting(ans.body, "acceleration"), 250.0, 1e-9);
    CHECK_NEAR(get_float(c, WSG_CMD_GET_ACCELERATION), 250.0, 1e-3);
}

/* A Loop (06h) packet with its checksum spoilt: E_CHECKSUM_ERROR, or
 * with CRC off E_SUCCESS. */
static int bad_crc_status(struct emu_client *c)
{
    uint8_t pkt[32], data[2] = {0x12, 0x34};
    struct wsg_client_frame f;
    size_t n = wsg_frame_encode(pkt, sizeof pkt, WSG_CMD_LOOP, data, 2);

    pkt[n - 1] ^= 0x5A;
    if (emu_send_raw(c, pkt, n) < 0)
        return -1;
    if (emu_recv_id(c, WSG_CMD_LOOP, &f, EMU_REPLY_MS) != 1)
        return -1;
    return f.status;
}

static void test_wire(struct emu *e, struct emu_client *c)
{
    struct emu_client c2;
    uint32_t flags = 0;
    char buf[256];
    long n;

    /* CRC, on a connection open before and after the change. */
    CHECK_EQ(bad_crc_status(c), WSG_E_CHECKSUM_ERROR);
    CHECK_EQ(post("/settings.json", "crc=off"), 200);
    CHECK_EQ(bad_crc_status(c), WSG_E_SUCCESS);
    CHECK_EQ(post("/settings.json", "crc=on"), 200);
    CHECK_EQ(bad_crc_status(c), WSG_E_CHECKSUM_ERROR);

    /* Error state on TCP disconnect: off, a close without 07h leaves no
     * FAST STOP; on again, it does. */
    CHECK_EQ(post("/settings.json", "disconnect-fast-stop=off"), 200);
    REQUIRE(emu_open(&c2, e, &emu_tcp) == 0);
    CHECK_EQ(emu_sync(&c2, EMU_REPLY_MS), 0);
    emu_close(&c2);
    emu_sleep_ms(EMU_QUIET_MS);
    CHECK(emu_get_flags(c, &flags) == 0 && !(flags & WSG_SF_FAST_STOP));
    CHECK_EQ(post("/settings.json", "disconnect-fast-stop=on"), 200);
    REQUIRE(emu_open(&c2, e, &emu_tcp) == 0);
    CHECK_EQ(emu_sync(&c2, EMU_REPLY_MS), 0);
    emu_close(&c2);
    CHECK_EQ(emu_wait_flags(c, WSG_SF_FAST_STOP, WSG_SF_FAST_STOP,
                            EMU_REPLY_MS, NULL),
             0);
    CHECK_EQ(
        emu_request(c, WSG_CMD_ACK_FAST_STOP, "ack", 3, NULL, EMU_REPLY_MS),
        WSG_E_SUCCESS);

    /* The text interface: the next connection speaks GCL, the open one
     * stays binary. */
    CHECK_EQ(post("/settings.json", "text-interface=on"), 200);
    REQUIRE(emu_open(&c2, e, &emu_tcp) == 0);
    CHECK_EQ(emu_send_raw(&c2, "POS?\n", 5), 0);
    n = emu_recv_raw(&c2, (uint8_t *)buf, sizeof buf - 1, EMU_REPLY_MS);
    CHECK(n > 0);
    if (n > 0) {
        buf[n] = '\0';
        CHECK(strncmp(buf, "POS=", 4) == 0);
    }
    CHECK_EQ(emu_sync(c, EMU_REPLY_MS), 0);
    CHECK_EQ(post("/settings.json", "text-interface=off"), 200);
    CHECK_EQ(emu_send_raw(&c2, "BYE()\n", 6), 0);
    emu_close(&c2);
    emu_sleep_ms(EMU_QUIET_MS);
    CHECK(emu_get_flags(c, &flags) == 0 && !(flags & WSG_SF_FAST_STOP));
}

static int motion(const char *body)
{
    return post("/motion", body);
}

static int has(const char *s)
{
    int ok = strstr(ans.body, s) != NULL;

    if (!ok)
        fprintf(stderr, "answer %d: %s (wanted %s)\n", ans.status, ans.body,
                s);
    return ok;
}

static void test_motion(struct emu_client *c, struct ctl *k)
{
    CHECK_EQ(motion("action=move&width=30&speed=100"), 409);
    CHECK(has("\"status\":\"E_NOT_INITIALIZED\""));
    CHECK_EQ(motion("action=fly"), 400);
    CHECK_EQ(motion("action=move&width=abc"), 400);

    CHECK_EQ(motion("action=home"), 202);
    CHECK(has("\"command\":\"20h\",\"status\":\"E_CMD_PENDING\""));
    CHECK_EQ(emu_wait_flags(c, WSG_SF_REFERENCED | WSG_SF_MOVING,
                            WSG_SF_REFERENCED, EMU_HOMING_MS, NULL),
             0);
    CHECK_EQ(motion("action=move&width=30&speed=200"), 202);
    CHECK(has("\"status\":\"E_CMD_PENDING\""));
    CHECK_EQ(motion("action=move&width=30&speed=200"), 409);
    CHECK(has("\"status\":\"E_ALREADY_RUNNING\""));
    wait_settled(c, 29.9f, 30.1f);
    CHECK_EQ(motion("action=jog&step=-5&speed=100"), 202);
    wait_settled(c, 24.9f, 25.1f);

    /* Grasp a part with a force limit of its own, release it. */
    CMD_OK(k, "part 20");
    CHECK_EQ(motion("action=grasp&width=20&speed=100&force=30"), 202);
    CHECK(has("\"command\":\"25h\""));
    CHECK_NEAR(get_float(c, WSG_CMD_GET_FORCE_LIMIT), 30.0, 1e-3);
    {
        double end = emu_now_ms() + EMU_MOVE_MS;

        while (emu_get_grasp_state(c) != WSG_GS_HOLDING && emu_now_ms() < end)
            emu_sleep_ms(20);
        CHECK_EQ(emu_get_grasp_state(c), WSG_GS_HOLDING);
    }
    CHECK_EQ(motion("action=release&pullback=10&speed=100"), 202);
    CHECK(has("\"command\":\"26h\""));
    wait_settled(c, 28.0f, 31.0f);
    CMD_OK(k, "part none");

    /* Stop a slow move. */
    CHECK_EQ(motion("action=move&width=100&speed=5"), 202);
    CHECK_EQ(motion("action=stop"), 200);
    CHECK(has("\"command\":\"22h\",\"status\":\"E_SUCCESS\""));
    CHECK_EQ(emu_wait_flags(c, WSG_SF_MOVING, 0, EMU_REPLY_MS, NULL), 0);
}

static void test_forms(struct emu_client *c)
{
    /* What LasseGoransson/wsg50-httpapi posts: every field, sender 1221. */
    CHECK_EQ(post("/motion.json",
                  "1207=40&1214=150&1247=0&1254=100&1261=80&1291=88&1298=100&"
                  "1334=2500&1341=50&1348=1&sender_id=1221&event_type=0"),
             202);
    CHECK(has("\"action\":\"move\""));
    wait_settled(c, 39.9f, 40.1f);
    /* The move alone: the configuration fields it carried are not taken. */
    CHECK_NEAR(get_float(c, WSG_CMD_GET_ACCELERATION), 250.0, 1e-3);
    CHECK_EQ(post("/motion.json",
                  "1334=500&1341=6&1348=2&sender_id=1355&event_type=0"),
             200);
    CHECK_NEAR(get_float(c, WSG_CMD_GET_ACCELERATION), 500.0, 1e-3);
    CHECK_EQ(post("/motion.json", "1207=40&sender_id=9"), 400);

    /* What Xamla's web_services.py posts: one field at a time. */
    CHECK_EQ(post("/graspconf.json", "253=2.5&sender_id=342&event_type=0"),
             200);
    CHECK_EQ(post("/graspconf.json", "260=8&sender_id=342&event_type=0"), 200);
    CHECK_EQ(post("/graspconf.json", "260=500&sender_id=342&event_type=0"),
             400);
    CHECK(has("clamping-travel: 500 mm is out of range"));
    CHECK_EQ(get_settings(), 200);
    CHECK_NEAR(setting(ans.body, "width-tolerance"), 2.5, 1e-9);
    CHECK_NEAR(setting(ans.body, "clamping-travel"), 8.0, 1e-9);
    CHECK_NEAR(setting(ans.body, "acceleration"), 500.0, 1e-9);
}

/* s as a form value: every byte but letters and digits as %XX. */
static void form_value(char *out, size_t cap, const char *s)
{
    static const char hex[] = "0123456789ABCDEF";
    size_t n = 0;

    for (; *s && n + 4 < cap; s++) {
        unsigned char ch = (unsigned char)*s;

        if ((ch >= 'a' && ch <= 'z') || (ch >= 'A' && ch <= 'Z') ||
            (ch >= '0' && ch <= '9')) {
            out[n++] = (char)ch;
        } else {
            out[n++] = '%';
            out[n++] = hex[ch >> 4];
            out[n++] = hex[ch & 15];
        }
    }
    out[n] = '\0';
}

/* The error of a POST, with every copy of path in it cut out: what it
 * says of any path alike. */
static void error_without(const char *path, char *out, size_t cap)
{
    const char *p = ans.body, *at;
    size_t n = 0, k;

    while ((at = strstr(p, path)) != NULL && n < cap - 1) {
        k = (size_t)(at - p);
        if (k > cap - 1 - n)
            k = cap - 1 - n;
        memcpy(out + n, p, k);
        n += k;
        p = at + strlen(path);
    }
    k = strlen(p);
    if (k > cap - 1 - n)
        k = cap - 1 - n;
    memcpy(out + n, p, k);
    out[n + k] = '\0';
}

/* The startup script (the script setting) from the page:
 * - a path with a line break in a directory's name (a readable file
 *   there) is refused, and saving it writes nothing: no line of the
 *   attacker's ("log = ...") gets into the config file;
 * - it is checked as the next start opens it, and one message says no
 *   for a path that is not there, a directory, a FIFO and a link alike,
 *   so the page does not tell which paths exist; a regular file is
 *   taken. */
static void test_script_setting(const char *config)
{
    char top[] = "/tmp/wsgemu-webforms.XXXXXX";
    char evil[1100], file[1100], fifo[600], link[600], missing[600];
    char before[4096], after[4096], body[4096], v[3400];
    char msg[4][1024];
    const char *bad[4];
    FILE *f;
    int i;

    REQUIRE(mkdtemp(top) != NULL);
    REQUIRE(emu_slurp(config, before, sizeof before) > 0);

    /* "TOP/a\nlog = TOP/victim\n#/s.lua": made directory by directory
     * below TOP; then a readable file in the last one. */
    {
        char dirs[1024];
        size_t k;

        snprintf(dirs, sizeof dirs, "%s/a\nlog = %s/victim\n#", top, top);
        for (k = strlen(top) + 1; dirs[k]; k++) {
            if (dirs[k] != '/')
                continue;
            dirs[k] = '\0';
            REQUIRE(mkdir(dirs, 0700) == 0);
            dirs[k] = '/';
        }
        REQUIRE(mkdir(dirs, 0700) == 0);
        REQUIRE((size_t)snprintf(evil, sizeof evil, "%s/s.lua", dirs) <
                sizeof evil);
    }
    f = fopen(evil, "w");
    REQUIRE(f && fputs("print('hi')\n", f) >= 0 && fclose(f) == 0);
    form_value(v, sizeof v, evil);
    snprintf(body, sizeof body, "script=%s&save=1", v);
    CHECK_EQ(post("/settings.json", body), 400);
    CHECK(has("control character"));
    REQUIRE(emu_slurp(config, after, sizeof after) > 0);
    CHECK(strcmp(before, after) == 0);
    CHECK(strstr(after, "log =") == NULL);
    CHECK_EQ(get_settings(), 200);
    CHECK(strstr(ans.body, "victim") == NULL);

    /* What is not a regular file, or not there: one message. */
    snprintf(missing, sizeof missing, "%s/none.lua", top);
    snprintf(fifo, sizeof fifo, "%s/fifo.lua", top);
    snprintf(link, sizeof link, "%s/link.lua", top);
    snprintf(file, sizeof file, "%s/good.lua", top);
    REQUIRE(mkfifo(fifo, 0600) == 0);
    f = fopen(file, "w");
    REQUIRE(f && fputs("print('hi')\n", f) >= 0 && fclose(f) == 0);
    REQUIRE(symlink(file, link) == 0);
    bad[0] = missing;
    bad[1] = top; /* a directory */
    bad[2] = fifo;
    bad[3] = link;
    for (i = 0; i < 4; i++) {
        form_value(v, sizeof v, bad[i]);
        snprintf(body, sizeof body, "script=%s", v);
        CHECK_EQ(post("/settings.json", body), 400);
        error_without(bad[i], msg[i], sizeof msg[i]);
        if (i > 0 && strcmp(msg[i], msg[0]) != 0)
            fprintf(stderr, "  \"%s\"\n  vs \"%s\"\n", msg[i], msg[0]);
        CHECK(i == 0 || strcmp(msg[i], msg[0]) == 0);
    }
    CHECK(strstr(msg[0], "script: cannot read") != NULL);
    form_value(v, sizeof v, file);
    snprintf(body, sizeof body, "script=%s", v);
    CHECK_EQ(post("/settings.json", body), 200);
    CHECK_EQ(post("/settings.json", "script="), 200);

    unlink(link);
    unlink(file);
    unlink(fifo);
    unlink(evil);
    /* The evil tree, from the bottom up. */
    snprintf(file, sizeof file, "%s", evil);
    while (strlen(file) > strlen(top)) {
        *strrchr(file, '/') = '\0';
        rmdir(file);
    }
    rmdir(top);
}

static void test_save(struct emu *e, struct emu_client *c, struct ctl *k,
                      const char *config)
{
    char text[4096];
    struct emu e2;
    struct emu_client c2;

    CHECK_EQ(post("/settings.json",
                  "crc=off&acceleration=350&force-limit=35&save=1"),
             200);
    CHECK(has("applied and saved to"));
    CHECK(emu_slurp(config, text, sizeof text) > 0);
    CHECK(strstr(text, "# cell 4\n") != NULL);
    /* In place of the old lines, the negation's too; appended after. */
    CHECK(strstr(text, "acceleration = 350\ncrc = off\nmodel = wsg50\n"
                       "force-limit = 35\n") != NULL);
    CHECK(strstr(text, "no-crc") == NULL);

    emu_close(c);
    ctl_close(k);
    CHECK_EQ(emu_stop(e), 0);
    start(&e2, config);
    REQUIRE(emu_open(&c2, &e2, &emu_tcp) == 0);
    CHECK_EQ(get_settings(), 200);
    CHECK_NEAR(setting(ans.body, "acceleration"), 350.0, 1e-9);
    CHECK_NEAR(setting(ans.body, "force-limit"), 35.0, 1e-9);
    CHECK_EQ((int)setting(ans.body, "crc"), 0);
    CHECK_NEAR(get_float(&c2, WSG_CMD_GET_ACCELERATION), 350.0, 1e-3);
    CHECK_EQ(bad_crc_status(&c2), WSG_E_SUCCESS);
    emu_close(&c2);
    CHECK_EQ(emu_stop(&e2), 0);

    /* No config file: nothing to save to, and nothing changes. */
    start(&e2, NULL);
    CHECK_EQ(post("/settings.json", "acceleration=400&save=1"), 400);
    CHECK(has("without a config file"));
    CHECK_EQ(get_settings(), 200);
    CHECK(strstr(ans.body, "\"config\":null") != NULL);
    CHECK_NEAR(setting(ans.body, "acceleration"), 150.0, 1e-9);
    CHECK_EQ(emu_stop(&e2), 0);
}

/* save=1 on a config file it must not replace: a symbolic link stays a
 * link (the file it names unchanged), a read-only file stays as it was,
 * and both are refused (409) with nothing changed; a file it may write
 * keeps its mode and (where the daemon may give it, as root) its owner. */
static void test_save_guarded(const char *config)
{
    char real[600], before[4096], after[4096];
    struct stat st;
    struct emu e;

    start(&e, config);

    /* Its mode and owner stay. */
    REQUIRE(chmod(config, 0640) == 0);
    if (geteuid() == 0)
        REQUIRE(chown(config, 4321, 4322) == 0);
    else
        printf("not root: the owner's part is not checked\n");
    CHECK_EQ(post("/settings.json", "acceleration=310&save=1"), 200);
    REQUIRE(lstat(config, &st) == 0);
    CHECK(S_ISREG(st.st_mode));
    CHECK_EQ(st.st_mode & 07777, 0640);
    if (geteuid() == 0) {
        CHECK_EQ(st.st_uid, 4321);
        CHECK_EQ(st.st_gid, 4322);
        REQUIRE(chown(config, 0, 0) == 0);
    }
    REQUIRE(emu_slurp(config, before, sizeof before) > 0);
    CHECK(strstr(before, "acceleration = 310\n") != NULL);

    /* Read-only: refused, the file and the settings as they were. */
    REQUIRE(chmod(config, 0444) == 0);
    CHECK_EQ(post("/settings.json", "acceleration=320&save=1"), 409);
    CHECK(has("read-only"));
    REQUIRE(emu_slurp(config, after, sizeof after) > 0);
    CHECK(strcmp(before, after) == 0);
    REQUIRE(stat(config, &st) == 0);
    CHECK_EQ(st.st_mode & 07777, 0444);
    CHECK_EQ(get_settings(), 200);
    CHECK_NEAR(setting(ans.body, "acceleration"), 310.0, 1e-9);
    REQUIRE(chmod(config, 0644) == 0);

    /* A link: refused, still a link, the file it names as it was. */
    snprintf(real, sizeof real, "%s.real", config);
    REQUIRE(rename(config, real) == 0);
    REQUIRE(symlink(real, config) == 0);
    CHECK_EQ(post("/settings.json", "acceleration=330&save=1"), 409);
    CHECK(has("symbolic link"));
    REQUIRE(lstat(config, &st) == 0);
    CHECK(S_ISLNK(st.st_mode));
    REQUIRE(emu_slurp(real, after, sizeof after) > 0);
    CHECK(strcmp(before, after) == 0);
    CHECK_EQ(get_settings(), 200);
    CHECK_NEAR(setting(ans.body, "acceleration"), 310.0, 1e-9);
    REQUIRE(unlink(config) == 0);
    REQUIRE(rename(real, config) == 0);
    CHECK_EQ(emu_stop(&e), 0);
}

int main(int argc, char **argv)
{
    char config[512];
    struct emu_client c;
    struct emu e;
    struct ctl k;

    exe = emu_exe(argc, argv);
    if (!WSG_TEST_HAVE_WEB)
        test_skip("wsgemu was built without libmicrohttpd");
    emu_temp_file(
        config, sizeof config, "webforms",
        "# cell 4\nacceleration = 200\nno-crc = off\nmodel = wsg50\n");
    start(&e, config);
    REQUIRE(ctl_open(&k, &e) == 0);
    REQUIRE(emu_open(&c, &e, &emu_tcp) == 0);

    test_read_back(&c, config);
    test_refused(&c);
    test_wire(&e, &c);
    test_motion(&c, &k);
    test_forms(&c);
    test_script_setting(config);
    test_save(&e, &c, &k, config);
    test_save_guarded(config);

    unlink(config);
    TEST_EXIT();
}
