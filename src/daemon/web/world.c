/*
 * The page's view of the world around the gripper: the communication log
 * as it happens, and the control channel's scenario commands (a part, an
 * obstacle, faults, paused and stepped time) from the Diagnostics tab.
 *
 * The log's lines come from the daemon's log (log.h) through its sink,
 * fed only while a page watches (an event stream is open): with no one
 * watching, no line is even made. They go into a ring that the event
 * stream reads (server.c).
 *
 * The scenario commands are the control channel's own: the page has a
 * control channel of its own that serves no socket (wsg_control_new), so
 * a command typed on the page does what it does over --control, answered
 * with the same line. All but `script run FILE`: on the page it runs a
 * script of the script directory by its name, as POST /script/run does,
 * for the page must not run (and so show the compile error of) any file
 * the daemon can read.
 */
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "impl.h"

static void on_log_line(void *ctx, const char *line, size_t len)
{
    wsg_web_log_line(ctx, line, len);
}

static void on_ctl_answer(void *ctx, const char *line, size_t len)
{
    struct wsg_web *web = ctx;
    size_t room = sizeof web->ctl_answer - 1 - web->ctl_answer_len;

    if (len > room)
        len = room;
    memcpy(web->ctl_answer + web->ctl_answer_len, line, len);
    web->ctl_answer_len += len;
    web->ctl_answer[web->ctl_answer_len] = '\0';
}

/* The page's `script run`: what POST /script/run runs, a script of the
 * script directory by its name, never any file the daemon can read (the
 * control channel's own takes a path). */
static int on_ctl_script_run(void *ctx, struct wsg_script *h, const char *file,
                             char *err, size_t errcap)
{
    unsigned status;
    char why[512];

    status = wsg_web_script_start(ctx, h, file, why, sizeof why);
    if (status == 0)
        return 0;
    /* A path, or a bad name: what the page takes instead. */
    if (status == MHD_HTTP_BAD_REQUEST)
        snprintf(err, errcap, "%s (the page runs NAME.lua of --script-dir)",
                 why);
    else
        snprintf(err, errcap, "%s", why);
    return -1;
}

int wsg_web_world_open(struct wsg_web *web)
{
    int r = wsg_control_new(&web->ctl, web->reactor, web->sched);

    if (r < 0)
        return r;
    wsg_control_session_init(&web->ctl_session, on_ctl_answer, web);
    web->ctl_session.script_run = on_ctl_script_run;
    return 0;
}

void wsg_web_world_close(struct wsg_web *web)
{
    if (web->d && web->d->log.sink_ctx == web)
        wsg_log_sink(&web->d->log, NULL, NULL);
    wsg_control_close(web->ctl);
    web->ctl = NULL;
    free(web->log_ring);
    web->log_ring = NULL;
}

void wsg_web_world_watch(struct wsg_web *web, int on)
{
    /* The ring stays when the last page closes: the next one opened
     * shows what came before (up to the ring's size). */
    if (on && !web->log_ring)
        web->log_ring = malloc(WSG_WEB_LOG_RING);
    if (on && web->log_ring)
        wsg_log_sink(&web->d->log, on_log_line, web);
    else
        wsg_log_sink(&web->d->log, NULL, NULL);
}

/* POST /control, line=<a control channel command>: its answer line as
 * {"ok":true|false,"answer":"..."} (400 for an "error ..." answer). */
enum MHD_Result wsg_web_serve_control(struct wsg_web *web,
                                      struct wsg_web_req *req)
{
    const char *line = wsg_web_field(req, "line");
    char esc[2 * WSG_WEB_ANSWER_MAX];
    size_t len;
    int ok;

    if (!line || !*line)
        return wsg_web_error(req->conn, MHD_HTTP_BAD_REQUEST,
                             "no command: post line=<command>, e.g. "
                             "line=part 40");
    len = strlen(line);
    if (len > WSG_CTL_LINE_MAX || strpbrk(line, "\r\n"))
        return wsg_web_error(req->conn, MHD_HTTP_BAD_REQUEST,
                             "one command line of at most 256 characters");
    web->ctl_answer_len = 0;
    web->ctl_answer[0] = '\0';
    wsg_control_input(web->ctl, &web->ctl_session, line, len);
    wsg_control_input(web->ctl, &web->ctl_session, "\n", 1);
    len = web->ctl_answer_len;
    while (len && web->ctl_answer[len - 1] == '\n')
        len--;
    wsg_web_escape(esc, sizeof esc, web->ctl_answer, len);
    ok = strncmp(web->ctl_answer, "ok", 2) == 0;
    return wsg_web_json(req->conn, ok ? MHD_HTTP_OK : MHD_HTTP_BAD_REQUEST,
                        "{\"ok\":%s,\"answer\":\"%s\"}", ok ? "true" : "false",
                        esc);
}
