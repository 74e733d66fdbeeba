/*
 * The page's settings (GET and POST /settings.json): the gripper's
 * settings a user changes on a real gripper's web page, changed on the
 * running daemon at once and, when asked, saved to the config file
 * (--config) so that they survive a restart.
 *
 * Each value is read by the options table (wsg_options_set), so it is
 * checked by the command line's rules and refused in the command line's
 * words; the ranges that depend on the model are the model's
 * (wsg_axis_config_range). A POST is all or nothing: every field is
 * checked on a copy of the options, the file is written, and only then
 * does anything change. The settings are the emulator's options, which
 * every gripper of a fleet was made from, so they change for every
 * gripper, as a restart with the saved file would have them.
 */
#define _GNU_SOURCE /* faccessat's AT_EACCESS */

#include <errno.h>
#include <fcntl.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "impl.h"
#include "script.h"

/* The settings of the page, in its order: the config file's keys (the
 * options table's names) and the labels of the real gripper's page. */
struct web_setting {
    const char *key;
    const char *label;
};

static const struct web_setting web_settings[] = {
    {"crc", "Enable CRC"},
    {"disconnect-fast-stop", "Enable error state on TCP disconnect"},
    {"text-interface", "Use text based interface (GCL on the TCP port)"},
    {"clamping-travel", "Clamping travel"},
    {"width-tolerance", "Part width tolerance"},
    {"acceleration", "Default acceleration"},
    {"force-limit", "Default force limit"},
    {"script", "Startup script (at the next start)"},
};

#define WEB_NSETTINGS (sizeof web_settings / sizeof web_settings[0])
/* The largest config file rewritten. */
#define WEB_CONFIG_MAX (1024u * 1024u)
/* The JSON of every setting, with two paths in it. */
#define WEB_SETTINGS_JSON_MAX 8192u

/* The options table's row of a key. */
static const struct wsg_setting *table_row(const char *key)
{
    size_t n, i;
    const struct wsg_setting *t = wsg_options_settings(&n);

    for (i = 0; i < n; i++)
        if (!t[i].cli_only && strcmp(t[i].name, key) == 0)
            return &t[i];
    return NULL;
}

static const void *opt_field(const struct wsg_options *o, size_t at)
{
    return (const char *)o + at - 1;
}

/* A model setting's value in a model's configuration. */
/* A setting's value as the config file has it: on|off, a number, a path;
 * "" for no startup script. */
static void value_text(const struct wsg_options *o,
                       const struct wsg_setting *s, char *buf, size_t cap)
{
    const char *text;

    switch (s->type) {
    case WSG_SETTING_BOOL:
        snprintf(buf, cap, "%s",
                 *(const int *)opt_field(o, s->at) ? "on" : "off");
        break;
    case WSG_SETTING_MODEL:
        snprintf(buf, cap, "%g", wsg_axis_config_get(&o->axis, s->quantity));
        break;
    default:
        text = *(const char *const *)opt_field(o, s->at);
        snprintf(buf, cap, "%s", text ? text : "");
        break;
    }
}

/* Appends to a fixed buffer; a cut shows as an overflow at the end. */
struct json_buf {
    char *p;
    size_t cap, len;
    int over;
};

static void jb_add(struct json_buf *b, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 2, 3)))
#endif
    ;

static void jb_add(struct json_buf *b, const char *fmt, ...)
{
    va_list ap;
    int n;

    if (b->over)
        return;
    va_start(ap, fmt);
    n = vsnprintf(b->p + b->len, b->cap - b->len, fmt, ap);
    va_end(ap);
    if (n < 0 || (size_t)n >= b->cap - b->len)
        b->over = 1;
    else
        b->len += (size_t)n;
}

/* A JSON string, or null for NULL. */
static void jb_str(struct json_buf *b, const char *s)
{
    char esc[2 * WSG_OPTIONS_PATH_MAX];

    if (!s) {
        jb_add(b, "null");
        return;
    }
    wsg_web_escape(esc, sizeof esc, s, strlen(s));
    jb_add(b, "\"%s\"", esc);
}

/* {"config":FILE|null,"grippers":N,"settings":[{...},...],"message":...}:
 * each setting with its key, label, type (bool, number, text), value, and
 * for a number its unit and the model's range. */
static enum MHD_Result answer_settings(struct wsg_web *web,
                                       struct MHD_Connection *conn,
                                       const char *message)
{
    const struct wsg_options *o = &web->d->opt;
    char out[WEB_SETTINGS_JSON_MAX];
    struct json_buf b = {out, sizeof out, 0, 0};
    char val[WSG_WEB_VALUE_MAX];
    size_t i;

    jb_add(&b, "{\"config\":");
    jb_str(&b, o->config_path);
    jb_add(&b, ",\"grippers\":%zu,\"settings\":[", web->d->ngrippers);
    for (i = 0; i < WEB_NSETTINGS; i++) {
        const struct wsg_setting *s = table_row(web_settings[i].key);

        if (!s)
            continue;
        jb_add(&b, "%s{\"name\":\"%s\",\"label\":", i ? "," : "", s->name);
        jb_str(&b, web_settings[i].label);
        value_text(o, s, val, sizeof val);
        if (s->type == WSG_SETTING_BOOL) {
            jb_add(&b, ",\"type\":\"bool\",\"value\":%s",
                   strcmp(val, "on") == 0 ? "true" : "false");
        } else if (s->type == WSG_SETTING_MODEL) {
            struct wsg_axis_range r =
                wsg_axis_config_range(&o->axis, s->quantity);

            jb_add(&b,
                   ",\"type\":\"number\",\"value\":%s,\"unit\":\"%s\","
                   "\"min\":%g,\"max\":%g",
                   val, s->unit, r.min, r.max);
        } else {
            jb_add(&b, ",\"type\":\"text\",\"value\":");
            jb_str(&b, val[0] ? val : NULL);
        }
        jb_add(&b, "}");
    }
    jb_add(&b, "]");
    if (message) {
        jb_add(&b, ",\"message\":");
        jb_str(&b, message);
    }
    jb_add(&b, "}");
    if (b.over)
        return wsg_web_error(conn, MHD_HTTP_INTERNAL_SERVER_ERROR,
                             "the settings do not fit the answer");
    return wsg_web_answer(conn, MHD_HTTP_OK, "application/json", out, b.len,
                          0);
}

/* The key of a config file's line ("  key = value"), NUL-terminated into
 * key; 0 for a blank line, a comment or no '='. */
static int line_key(const char *line, size_t len, char *key, size_t cap)
{
    const char *p = line, *end = line + len, *eq, *k;

    while (p < end && (*p == ' ' || *p == '\t'))
        p++;
    if (p == end || *p == '#')
        return 0;
    eq = memchr(p, '=', (size_t)(end - p));
    if (!eq)
        return 0;
    k = eq;
    while (k > p && (k[-1] == ' ' || k[-1] == '\t'))
        k--;
    if ((size_t)(k - p) >= cap)
        return 0;
    memcpy(key, p, (size_t)(k - p));
    key[k - p] = '\0';
    return 1;
}

/* The config file at path with the given settings' values from o: the
 * line of each (or of its negation: "no-crc = on") rewritten in place,
 * a second one of the same setting dropped (the file's last one would
 * win), the missing ones appended; no startup script drops its lines.
 * Comments and the other lines stay as they are. Written to a file
 * beside it with the file's owner and mode and renamed over it, so a
 * reader never sees half a file. Refused: a symbolic link (-ELOOP), what
 * is not a regular file (-ENOEXEC), a file the daemon may not write or
 * that has no write bit (-EACCES, -EROFS), one whose owner the daemon
 * may not give the new file (-EPERM). A
 * value with a line break is never written (-EILSEQ): it would be a line
 * of its own, any key = value (the options refuse one before this). 0
 * or -errno. */
static int save_config(const char *path, const struct wsg_options *o,
                       const int *given)
{
    const struct wsg_setting *rows[WEB_NSETTINGS];
    int written[WEB_NSETTINGS] = {0};
    char *in = NULL, *out = NULL, *tmp = NULL;
    size_t in_len = 0, out_len = 0, out_cap, i, n;
    struct stat st;
    FILE *f;
    int fd, r;

    for (i = 0; i < WEB_NSETTINGS; i++)
        rows[i] = table_row(web_settings[i].key);
    /* A link is not replaced by a file, nor a file the daemon may not
     * write overwritten (a read-only one: no write bit at all, whoever
     * the daemon runs as). */
    fd = open(path, O_RDONLY | O_NOFOLLOW | O_NONBLOCK | O_CLOEXEC);
    if (fd < 0)
        return -errno;
    f = fdopen(fd, "r");
    if (!f) {
        r = -errno;
        close(fd);
        return r;
    }
    r = fstat(fileno(f), &st) < 0 ? -errno : 0;
    if (r == 0 && !S_ISREG(st.st_mode))
        r = -ENOEXEC;
    if (r == 0 && faccessat(AT_FDCWD, path, W_OK, AT_EACCESS) < 0)
        r = errno == EROFS ? -EROFS : -EACCES;
    if (r == 0 && !(st.st_mode & 0222))
        r = -EACCES;
    if (r == 0 && st.st_size > (off_t)WEB_CONFIG_MAX)
        r = -EFBIG;
    if (r == 0) {
        in = malloc((size_t)st.st_size + 1);
        if (!in)
            r = -ENOMEM;
    }
    if (r == 0) {
        in_len = fread(in, 1, (size_t)st.st_size, f);
        if (ferror(f))
            r = -EIO;
    }
    fclose(f);
    if (r < 0)
        goto out;
    /* Each line at most as long as before, or a setting's line. */
    out_cap = in_len + WEB_NSETTINGS * (WSG_WEB_VALUE_MAX + 64) + 2;
    out = malloc(out_cap);
    tmp = malloc(strlen(path) + 8);
    if (!out || !tmp) {
        r = -ENOMEM;
        goto out;
    }
    for (i = 0; i < in_len; i += n) {
        const char *line = in + i, *nl = memchr(line, '\n', in_len - i);
        char key[64], val[WSG_WEB_VALUE_MAX];
        const struct wsg_setting *s;
        size_t k;
        int keep = 1;

        n = nl ? (size_t)(nl - line) + 1 : in_len - i;
        if (line_key(line, n, key, sizeof key) && (s = table_row(key))) {
            for (k = 0; k < WEB_NSETTINGS; k++) {
                if (!given[k] || !rows[k] || rows[k]->at != s->at)
                    continue;
                keep = 0;
                value_text(o, rows[k], val, sizeof val);
                if (strpbrk(val, "\r\n")) {
                    r = -EILSEQ;
                    goto out;
                }
                if (!written[k] && val[0])
                    out_len += (size_t)sprintf(out + out_len, "%s = %s\n",
                                               rows[k]->name, val);
                written[k] = 1;
            }
        }
        if (keep) {
            memcpy(out + out_len, line, n);
            out_len += n;
            if (!nl)
                out[out_len++] = '\n';
        }
    }
    for (i = 0; i < WEB_NSETTINGS; i++) {
        char val[WSG_WEB_VALUE_MAX];

        if (!given[i] || written[i] || !rows[i])
            continue;
        value_text(o, rows[i], val, sizeof val);
        if (strpbrk(val, "\r\n")) {
            r = -EILSEQ;
            goto out;
        }
        if (val[0])
            out_len += (size_t)sprintf(out + out_len, "%s = %s\n",
                                       rows[i]->name, val);
    }
    sprintf(tmp, "%s.new", path);
    r = wsg_web_replace_file(AT_FDCWD, path, tmp, out, out_len, &st);
out:
    free(tmp);
    free(out);
    free(in);
    return r;
}

/* A startup script the next start could not open would stop it: refused
 * now, while the user is there to see why. Opened as the start will open
 * it (wsg_script_open: no link followed, a regular file). One message for
 * every reason (none there, unreadable, a directory, a link, ...): the
 * page must not tell whether any path exists. */
static int script_check(const char *path, char *err, size_t errcap)
{
    int fd = wsg_script_open(path, NULL, 0);

    if (fd >= 0) {
        close(fd);
        return 0;
    }
    snprintf(err, errcap,
             "script: cannot read '%s' as a startup script (a regular file "
             "the emulator may read, not a link)",
             path);
    return -EINVAL;
}

/* Make the checked values of o the running daemon's: the options (what
 * GET shows and a fleet's next gripper would be made from), every
 * gripper's device, axis and transports. */
static void apply(struct wsg_web *web, const struct wsg_options *o,
                  const int *given, const char *script)
{
    struct wsg_daemon *d = web->d;
    unsigned model = 0;
    size_t k;

    for (k = 0; k < WEB_NSETTINGS; k++) {
        const struct wsg_setting *s = table_row(web_settings[k].key);

        if (!given[k] || !s)
            continue;
        if (s->type == WSG_SETTING_MODEL)
            model |= 1u << s->quantity;
        if (s->type == WSG_SETTING_BOOL)
            *(int *)((char *)&d->opt + s->at - 1) =
                *(const int *)opt_field(o, s->at);
        else if (s->type == WSG_SETTING_MODEL)
            *(struct wsg_model_value *)((char *)&d->opt + s->at - 1) =
                *(const struct wsg_model_value *)opt_field(o, s->at);
        else {
            snprintf(web->script_path, sizeof web->script_path, "%s", script);
            d->opt.script_path = script[0] ? web->script_path : NULL;
        }
    }
    d->opt.axis = o->axis;
    wsg_daemon_reconfigure(d, model);
}

/* Why save_config refused, for the page. */
static const char *save_error(int r)
{
    switch (r) {
    case -ELOOP:
        return "it is a symbolic link, which saving would replace by a "
               "file (give --config the file it names)";
    case -ENOEXEC:
        return "it is not a regular file";
    case -EACCES:
    case -EROFS:
        return "it is read-only to the emulator";
    case -EPERM:
        return "it belongs to a user or group the emulator may not give "
               "the saved file";
    case -EILSEQ:
        return "a value holds a line break";
    default:
        return strerror(-r);
    }
}

int wsg_web_settings_apply(struct wsg_web *web,
                           const struct wsg_web_field *fields, size_t n,
                           int save, char *err, size_t errcap)
{
    struct wsg_options *o;
    int given[WEB_NSETTINGS] = {0};
    const char *script = "";
    size_t i, k;
    int r = 0;

    if (save && !web->d->opt.config_path) {
        snprintf(err, errcap,
                 "cannot save: the emulator was started without a config "
                 "file (--config FILE); the settings were not changed");
        return -EINVAL;
    }
    o = malloc(sizeof *o);
    if (!o) {
        snprintf(err, errcap, "out of memory");
        return -ENOMEM;
    }
    /* Checked on a copy: nothing changes unless every field is good. */
    *o = web->d->opt;
    for (i = 0; i < n && r == 0; i++) {
        const struct wsg_web_field *fl = &fields[i];

        for (k = 0; k < WEB_NSETTINGS; k++)
            if (strcmp(fl->name, web_settings[k].key) == 0)
                break;
        if (k == WEB_NSETTINGS) {
            snprintf(err, errcap,
                     "unknown setting '%s' (the page's settings: crc, "
                     "disconnect-fast-stop, text-interface, clamping-travel, "
                     "width-tolerance, acceleration, force-limit, script)",
                     fl->name);
            r = -EINVAL;
            break;
        }
        given[k] = 1;
        if (strcmp(fl->name, "script") == 0 && !fl->value[0]) {
            /* Empty: no startup script (the real page's checkbox off). */
            script = "";
            o->script_path = NULL;
            continue;
        }
        r = wsg_options_set(o, fl->name, fl->value, err, errcap);
        if (r == 0 && strcmp(fl->name, "script") == 0) {
            script = fl->value;
            r = script_check(script, err, errcap);
        }
    }
    if (r == 0 && save) {
        r = save_config(web->d->opt.config_path, o, given);
        if (r < 0) {
            snprintf(err, errcap,
                     "cannot save to %s: %s; the settings were not changed",
                     web->d->opt.config_path, save_error(r));
            r = r == -EINVAL ? -EIO : r;
        }
    }
    if (r == 0)
        apply(web, o, given, script);
    free(o);
    return r;
}

static enum MHD_Result serve_post(struct wsg_web *web, struct wsg_web_req *req)
{
    struct wsg_web_field fields[WSG_WEB_FIELDS_MAX];
    const char *save = wsg_web_field(req, "save");
    int saving = save && strcmp(save, "1") == 0;
    char err[768], msg[WSG_OPTIONS_PATH_MAX + 64];
    size_t i, n = 0;
    int r;

    if (req->overfull)
        return wsg_web_error(req->conn, MHD_HTTP_BAD_REQUEST,
                             "a field too long, or too many fields");
    if (save && !saving && strcmp(save, "0") != 0)
        return wsg_web_error(req->conn, MHD_HTTP_BAD_REQUEST,
                             "save: '1' saves to the config file, '0' or "
                             "nothing does not");
    for (i = 0; i < req->nfields; i++)
        if (strcmp(req->fields[i].name, "save") != 0)
            fields[n++] = req->fields[i];
    r = wsg_web_settings_apply(web, fields, n, saving, err, sizeof err);
    /* 409: the config file is in a state the save must not change (a
     * link, read-only, another's). */
    if (r < 0)
        return wsg_web_error(req->conn,
                             r == -EINVAL ? MHD_HTTP_BAD_REQUEST
                             : r == -ELOOP || r == -ENOEXEC || r == -EACCES ||
                                     r == -EROFS || r == -EPERM
                                 ? MHD_HTTP_CONFLICT
                                 : MHD_HTTP_INTERNAL_SERVER_ERROR,
                             err);
    if (saving)
        snprintf(msg, sizeof msg, "applied and saved to %s",
                 web->d->opt.config_path);
    else
        snprintf(msg, sizeof msg, "applied (not saved)");
    return answer_settings(web, req->conn, msg);
}

enum MHD_Result wsg_web_serve_settings(struct wsg_web *web,
                                       struct wsg_web_req *req)
{
    if (req->method == WSG_WEB_POST)
        return serve_post(web, req);
    return answer_settings(web, req->conn, NULL);
}
