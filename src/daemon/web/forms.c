/*
 * The page's motion: the Motion tab's buttons (POST /motion) and the
 * forms public code posts to a real gripper (POST /motion.json and POST
 * /graspconf.json, with the numbered fields of its page).
 *
 * A motion runs as the binary command it stands for (20h homing, 21h
 * preposition, 22h stop, 25h grasp, 26h release, 32h force limit) through
 * the device's dispatcher, as GCL runs its commands: the command table's
 * checks and error codes are the page's too, and the answer is the
 * status the command's immediate reply carries. The page's session has a
 * tag no interface resolves, so a motion's final result goes to no one:
 * the page watches the state instead. The configuration fields go to the
 * settings (settings.c), checked and applied as POST /settings.json
 * applies them.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "impl.h"

/* Transport number 15: past every gripper's transports (at most
 * WSG_TRANSPORT_MAX), so the lookup of a final result finds no one. */
#define WEB_SESSION_TAG ((15u << WSG_TAG_TRANSPORT_SHIFT) | 1u)

/* The sender_id of each button of the real page's motion form (the field
 * after its inputs: 1221 follows 1207 and 1214). */
#define FORM_MOVE    1221
#define FORM_GRASP   1268
#define FORM_RELEASE 1305
#define FORM_CONFIG  1355

/* The immediate answer of the command being run. */
struct web_cmd {
    uint8_t id;
    int answered;
    uint16_t status;
};

static void on_answer(void *ctx, struct wsg_session *s, uint8_t id,
                      uint16_t status, const uint8_t *params, size_t len)
{
    struct web_cmd *c = ctx;

    (void)s;
    (void)params;
    (void)len;
    if (!c->answered && id == c->id) {
        c->answered = 1;
        c->status = status;
    }
}

/* Nothing is sent as packets: the format hook takes every answer. */
static void no_send(struct wsg_session *s, const uint8_t *pkt, size_t len)
{
    (void)s;
    (void)pkt;
    (void)len;
}

/* Run command id with its payload through the dispatcher of the page's
 * gripper; the status of its immediate reply. The caller touches the
 * gripper before and is done with it after. */
static uint16_t run_cmd(struct wsg_web *web, uint8_t id, const uint8_t *p,
                        size_t len)
{
    struct web_cmd c = {id, 0, WSG_E_CMD_FAILED};
    struct wsg_session s;
    struct wsg_frame f;

    wsg_session_init(&s, WEB_SESSION_TAG, 0, no_send, NULL);
    snprintf(s.peer, sizeof s.peer, "web");
    s.format = on_answer;
    s.format_ctx = &c;
    f.id = id;
    f.len = (uint16_t)len;
    f.payload = p;
    wsg_device_dispatch(&web->g->dev, &s, &f);
    return c.status;
}

/* A number field: 1 (into *v), 0 when absent or empty (*v = def), -1 when
 * it is not a finite decimal number. */
static int num_field(const struct wsg_web_req *req, const char *name,
                     double def, double *v)
{
    const char *s = wsg_web_field(req, name);
    char *end;

    *v = def;
    if (!s || !*s)
        return 0;
    *v = strtod(s, &end);
    if (*end || end == s || !isfinite(*v) || strpbrk(s, "xXnNiI"))
        return -1;
    return 1;
}

/* The HTTP status of a command's status: accepted (a motion started,
 * E_CMD_PENDING) 202, done 200, a bad value 400, the gripper's state in
 * the way (FAST STOP, not homed, moving) 409. */
static unsigned http_status(uint16_t st)
{
    switch (st) {
    case WSG_E_SUCCESS:
        return MHD_HTTP_OK;
    case WSG_E_CMD_PENDING:
        return MHD_HTTP_ACCEPTED;
    case WSG_E_INVALID_PARAMETER:
    case WSG_E_RANGE_ERROR:
    case WSG_E_CMD_FORMAT_ERROR:
    case WSG_E_NO_PARAM_EXPECTED:
        return MHD_HTTP_BAD_REQUEST;
    default:
        return MHD_HTTP_CONFLICT;
    }
}

static enum MHD_Result answer(struct wsg_web_req *req, const char *action,
                              uint8_t id, uint16_t st)
{
    return wsg_web_json(req->conn, http_status(st),
                        "{\"action\":\"%s\",\"command\":\"%02Xh\","
                        "\"status\":\"%s\"}",
                        action, id, wsg_status_name(st));
}

static size_t put_width_speed(uint8_t *p, double width, double speed)
{
    wsg_put_f32(p, (float)width);
    wsg_put_f32(p + 4, (float)speed);
    return 8;
}

/* One motion: a preposition (flags 0 or relative), a grasp with its
 * force limit first (force < 0: the limit as it is), a release. */
static enum MHD_Result do_motion(struct wsg_web *web, struct wsg_web_req *req,
                                 const char *action, uint8_t id, uint8_t flags,
                                 double width, double speed, double force)
{
    uint8_t p[9];
    size_t n = 0;
    uint16_t st = WSG_E_SUCCESS;

    wsg_web_touch(web);
    if (force >= 0) {
        wsg_put_f32(p, (float)force);
        st = run_cmd(web, WSG_CMD_SET_FORCE_LIMIT, p, 4);
        if (st != WSG_E_SUCCESS)
            id = WSG_CMD_SET_FORCE_LIMIT;
    }
    if (st == WSG_E_SUCCESS) {
        if (id == WSG_CMD_PREPOSITION)
            p[n++] = flags;
        n += put_width_speed(p + n, width, speed);
        st = run_cmd(web, id, p, n);
    }
    wsg_web_done(web);
    return answer(req, action, id, st);
}

static enum MHD_Result bad_field(struct wsg_web_req *req, const char *name,
                                 const char *what)
{
    char msg[256];

    snprintf(msg, sizeof msg, "%s: %s", name, what);
    return wsg_web_error(req->conn, MHD_HTTP_BAD_REQUEST, msg);
}

/* POST /motion: action=move|jog|grasp|release|home|stop. */
enum MHD_Result wsg_web_serve_motion(struct wsg_web *web,
                                     struct wsg_web_req *req)
{
    const char *action = wsg_web_field(req, "action");
    const struct wsg_axis *ax = wsg_device_axis_const(&web->g->dev);
    double width, speed, force, step, pull;
    uint8_t dir = WSG_HOME_DEFAULT;
    uint16_t st;
    uint8_t id;

    if (!action)
        return wsg_web_error(req->conn, MHD_HTTP_BAD_REQUEST,
                             "action: one of move, jog, grasp, release, "
                             "home, stop");
    if (num_field(req, "speed", WSG_GCL_DEFAULT_SPEED, &speed) < 0)
        return bad_field(req, "speed", "not a number of mm/s");
    if (strcmp(action, "move") == 0) {
        if (num_field(req, "width", 0, &width) != 1)
            return bad_field(req, "width", "a target width in mm is needed");
        return do_motion(web, req, action, WSG_CMD_PREPOSITION, 0, width,
                         speed, -1);
    }
    if (strcmp(action, "jog") == 0) {
        if (num_field(req, "step", 0, &step) != 1)
            return bad_field(req, "step",
                             "a step in mm is needed (negative closes)");
        return do_motion(web, req, action, WSG_CMD_PREPOSITION,
                         WSG_MOVE_RELATIVE, step, speed, -1);
    }
    if (strcmp(action, "grasp") == 0) {
        if (num_field(req, "width", 0, &width) != 1)
            return bad_field(req, "width", "a part width in mm is needed");
        if (num_field(req, "force", -1, &force) < 0 ||
            (wsg_web_field(req, "force") && force < 0))
            return bad_field(req, "force", "not a force limit in N");
        return do_motion(web, req, action, WSG_CMD_GRASP, 0, width, speed,
                         force);
    }
    if (strcmp(action, "release") == 0) {
        if (num_field(req, "pullback", web->d->opt.release_pullback, &pull) <
            0)
            return bad_field(req, "pullback", "not a number of mm");
        /* Open by the pull-back from where the fingers are, as GCL's
         * RELEASE() does; the model clamps it to the stroke. */
        wsg_web_touch(web);
        width = wsg_axis_width(ax) + pull;
        wsg_web_done(web);
        return do_motion(web, req, action, WSG_CMD_RELEASE, 0, width, speed,
                         -1);
    }
    if (strcmp(action, "home") == 0 || strcmp(action, "stop") == 0) {
        id = action[0] == 'h' ? WSG_CMD_HOMING : WSG_CMD_STOP;
        wsg_web_touch(web);
        st = run_cmd(web, id, &dir, id == WSG_CMD_HOMING ? 1 : 0);
        wsg_web_done(web);
        return answer(req, action, id, st);
    }
    return wsg_web_error(req->conn, MHD_HTTP_BAD_REQUEST,
                         "action: one of move, jog, grasp, release, home, "
                         "stop");
}

/* Settings fields of a form, under their config file keys. */
struct form_setting {
    const char *field; /* "1334" */
    const char *key;   /* "acceleration" */
};

static enum MHD_Result apply_form_settings(struct wsg_web *web,
                                           struct wsg_web_req *req,
                                           const struct form_setting *fs,
                                           size_t nfs, const char *action)
{
    struct wsg_web_field fields[4];
    char err[768], esc[1600];
    size_t i, n = 0;
    const char *v;

    for (i = 0; i < nfs && n < sizeof fields / sizeof fields[0]; i++) {
        v = wsg_web_field(req, fs[i].field);
        if (!v)
            continue;
        snprintf(fields[n].name, sizeof fields[n].name, "%s", fs[i].key);
        snprintf(fields[n].value, sizeof fields[n].value, "%s", v);
        n++;
    }
    if (n == 0)
        return wsg_web_error(req->conn, MHD_HTTP_BAD_REQUEST,
                             "no setting in the form");
    if (wsg_web_settings_apply(web, fields, n, 0, err, sizeof err) < 0) {
        /* The form's own field number with the setting's words. */
        return wsg_web_error(req->conn, MHD_HTTP_BAD_REQUEST, err);
    }
    wsg_web_escape(esc, sizeof esc, action, strlen(action));
    return wsg_web_json(req->conn, MHD_HTTP_OK,
                        "{\"action\":\"%s\",\"status\":\"%s\"}", esc,
                        wsg_status_name(WSG_E_SUCCESS));
}

/* POST /motion.json: the motion form of the real page; sender_id says
 * which of its buttons was pressed. */
enum MHD_Result wsg_web_serve_motion_form(struct wsg_web *web,
                                          struct wsg_web_req *req)
{
    static const struct form_setting config[] = {
        {"1334", "acceleration"},
        {"1341", "clamping-travel"},
        {"1348", "width-tolerance"},
    };
    const char *sender = wsg_web_field(req, "sender_id");
    double width, speed, force;
    long id = sender ? strtol(sender, NULL, 10) : FORM_MOVE;

    switch (id) {
    case FORM_MOVE:
        if (num_field(req, "1207", 0, &width) != 1)
            return bad_field(req, "1207", "a target width in mm is needed");
        if (num_field(req, "1214", WSG_GCL_DEFAULT_SPEED, &speed) < 0)
            return bad_field(req, "1214", "not a number of mm/s");
        return do_motion(web, req, "move", WSG_CMD_PREPOSITION, 0, width,
                         speed, -1);
    case FORM_GRASP:
        if (num_field(req, "1247", 0, &width) != 1)
            return bad_field(req, "1247", "a part width in mm is needed");
        if (num_field(req, "1254", WSG_GCL_DEFAULT_SPEED, &speed) < 0)
            return bad_field(req, "1254", "not a number of mm/s");
        if (num_field(req, "1261", -1, &force) < 0 ||
            (wsg_web_field(req, "1261") && force < 0))
            return bad_field(req, "1261", "not a force limit in N");
        return do_motion(web, req, "grasp", WSG_CMD_GRASP, 0, width, speed,
                         force);
    case FORM_RELEASE:
        if (num_field(req, "1291", 0, &width) != 1)
            return bad_field(req, "1291", "an open width in mm is needed");
        if (num_field(req, "1298", WSG_GCL_DEFAULT_SPEED, &speed) < 0)
            return bad_field(req, "1298", "not a number of mm/s");
        return do_motion(web, req, "release", WSG_CMD_RELEASE, 0, width, speed,
                         -1);
    case FORM_CONFIG:
        return apply_form_settings(
            web, req, config, sizeof config / sizeof config[0], "configure");
    default:
        return bad_field(req, "sender_id",
                         "1221 (move), 1268 (grasp), 1305 (release) or "
                         "1355 (motion configuration)");
    }
}

/* POST /graspconf.json: 253 part width tolerance, 260 clamping travel
 * (one or both), sender_id 342. */
enum MHD_Result wsg_web_serve_graspconf(struct wsg_web *web,
                                        struct wsg_web_req *req)
{
    static const struct form_setting grasp[] = {
        {"253", "width-tolerance"},
        {"260", "clamping-travel"},
    };

    return apply_form_settings(web, req, grasp, sizeof grasp / sizeof grasp[0],
                               "graspconf");
}
