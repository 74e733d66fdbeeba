/*
 * The page's scripting: the script directory (--script-dir, the gripper's
 * /user) as a file manager (GET /scripts.json; GET, PUT and DELETE
 * /scripts/NAME) and the script host driven from it (POST /script/run
 * and /script/stop; GET /script/status and /script/output).
 *
 * Names are plain file names ending in .lua (name_check), and the
 * directory is opened once per request: every file operation is relative
 * to that descriptor (openat, renameat, unlinkat) and follows no symbolic
 * link, so neither a name nor a link planted in the directory leads out
 * of it. A script is run from the descriptor that opened it, so a link
 * swapped in after the check cannot lead out either. An upload is written
 * to a hidden temporary file and renamed over the name, so a script is
 * never seen half written (a running script's `require` included).
 * Uploads are bounded: the directory's scripts may take --script-quota
 * bytes and be --script-files in number after one.
 */
#define _GNU_SOURCE

#include <dirent.h>
#include <errno.h>
#include <fcntl.h>
#include <limits.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "impl.h"
#include "wsg/proto.h"

/* 422: a script that does not compile; older MHDs name it otherwise. */
#define HTTP_UNPROCESSABLE 422u

/* The longest script name, ".lua" included. */
#define SCRIPT_NAME_MAX 64u
/* Scripts listed at most: a directory filled by hand could hold more
 * than a page can show ("more" tells how many were left out). */
#define SCRIPT_LIST_MAX 1024u
/* One entry of the list: the name escaped and two numbers. */
#define SCRIPT_ENTRY_MAX (SCRIPT_NAME_MAX + 96u)
/* GET /script/status: the script's file name (any name the control
 * channel ran: up to NAME_MAX bytes, 6 each escaped at worst) and its
 * error (the host keeps 511 bytes: all of them escaped at worst; a
 * longer one is cut), each escaped with its NUL. */
#define STATUS_NAME_MAX  (6u * NAME_MAX + 1u)
#define STATUS_ERROR_MAX (6u * 512u + 1u)

struct script_entry {
    char name[SCRIPT_NAME_MAX + 1];
    long long size;
    long long mtime;
};

/* 0 when name is one the directory may hold: letters, digits, '_', '.'
 * and '-', ending in ".lua", not starting with a dot (the upload's
 * temporary files do), at most SCRIPT_NAME_MAX bytes. Else -EINVAL with
 * the reason in why. */
static int name_check(const char *name, char *why, size_t cap)
{
    size_t n = strlen(name), i;

    if (n == 0) {
        snprintf(why, cap, "no script name");
        return -EINVAL;
    }
    if (n > SCRIPT_NAME_MAX) {
        snprintf(why, cap, "a script name has at most %u characters",
                 SCRIPT_NAME_MAX);
        return -EINVAL;
    }
    for (i = 0; i < n; i++) {
        char ch = name[i];

        if (!((ch >= 'a' && ch <= 'z') || (ch >= 'A' && ch <= 'Z') ||
              (ch >= '0' && ch <= '9') || ch == '_' || ch == '.' ||
              ch == '-')) {
            snprintf(why, cap,
                     "a script name has only letters, digits, '_', '.' and "
                     "'-' (no directories): NAME.lua");
            return -EINVAL;
        }
    }
    if (name[0] == '.') {
        snprintf(why, cap, "a script name does not start with a dot");
        return -EINVAL;
    }
    if (n < 5 || strcmp(name + n - 4, ".lua") != 0) {
        snprintf(why, cap, "a script name ends in .lua");
        return -EINVAL;
    }
    return 0;
}

/* The script directory, opened for one request: its descriptor, or
 * -errno (-ENXIO: no --script-dir). */
static int dir_open(const struct wsg_web *web)
{
    const char *dir = web->d->opt.script_dir;
    int fd;

    if (!dir)
        return -ENXIO;
    fd = open(dir, O_RDONLY | O_DIRECTORY | O_CLOEXEC);
    return fd < 0 ? -errno : fd;
}

/* Why dir_open failed, as the answer: 409, the server is not set up for
 * it (no directory, or one that is not there). */
static enum MHD_Result dir_error(const struct wsg_web *web,
                                 struct MHD_Connection *conn, int err)
{
    char msg[PATH_MAX + 128];

    if (err == -ENXIO)
        return wsg_web_error(conn, MHD_HTTP_CONFLICT,
                             "no script directory: start wsgemu with "
                             "--script-dir DIR");
    snprintf(msg, sizeof msg, "script directory %s: %s",
             web->d->opt.script_dir, strerror(-err));
    return wsg_web_error(conn, MHD_HTTP_CONFLICT, msg);
}

/* A file of the directory for name, not following a link: 0 with *st, or
 * the answer's status (404 none, 403 not a regular file) with the reason
 * in why. */
static unsigned file_stat(int dfd, const char *name, struct stat *st,
                          char *why, size_t cap)
{
    if (fstatat(dfd, name, st, AT_SYMLINK_NOFOLLOW) < 0) {
        snprintf(why, cap, "%s: %s", name, strerror(errno));
        return errno == ENOENT ? MHD_HTTP_NOT_FOUND
                               : MHD_HTTP_INTERNAL_SERVER_ERROR;
    }
    if (!S_ISREG(st->st_mode)) {
        snprintf(why, cap,
                 "%s is not a regular file of the script "
                 "directory (a link or a directory): not touched",
                 name);
        return MHD_HTTP_FORBIDDEN;
    }
    return 0;
}

static int entry_cmp(const void *a, const void *b)
{
    return strcmp(((const struct script_entry *)a)->name,
                  ((const struct script_entry *)b)->name);
}

/* GET /scripts.json: {"dir":"...","scripts":[{"name","size","mtime"}],
 * "more":N}, sorted by name: the regular files with a script's name. */
enum MHD_Result wsg_web_serve_scripts(struct wsg_web *web,
                                      struct wsg_web_req *req)
{
    struct script_entry *list = NULL;
    size_t n = 0, more = 0, i, cap, used = 0;
    char why[512], *json = NULL, dir_esc[2 * PATH_MAX];
    enum MHD_Result ret = MHD_NO;
    struct dirent *de;
    struct stat st;
    DIR *dir = NULL;
    int dfd;

    dfd = dir_open(web);
    if (dfd < 0)
        return dir_error(web, req->conn, dfd);
    dir = fdopendir(dfd);
    if (!dir) {
        close(dfd);
        return dir_error(web, req->conn, -errno);
    }
    list = malloc(SCRIPT_LIST_MAX * sizeof *list);
    if (!list)
        goto out_oom;
    while ((de = readdir(dir)) != NULL) {
        if (name_check(de->d_name, why, sizeof why) < 0 ||
            file_stat(dirfd(dir), de->d_name, &st, why, sizeof why) != 0)
            continue;
        if (n == SCRIPT_LIST_MAX) {
            more++;
            continue;
        }
        strcpy(list[n].name, de->d_name);
        list[n].size = (long long)st.st_size;
        list[n].mtime = (long long)st.st_mtime;
        n++;
    }
    qsort(list, n, sizeof *list, entry_cmp);
    wsg_web_escape(dir_esc, sizeof dir_esc, web->d->opt.script_dir,
                   strlen(web->d->opt.script_dir));
    cap = strlen(dir_esc) + 64 + n * SCRIPT_ENTRY_MAX;
    json = malloc(cap);
    if (!json)
        goto out_oom;
    used += (size_t)snprintf(json + used, cap - used,
                             "{\"dir\":\"%s\",\"scripts\":[", dir_esc);
    /* The names need no escape: name_check let only safe bytes by. */
    for (i = 0; i < n; i++)
        used += (size_t)snprintf(
            json + used, cap - used,
            "%s{\"name\":\"%s\",\"size\":%lld,\"mtime\":%lld}", i ? "," : "",
            list[i].name, list[i].size, list[i].mtime);
    used += (size_t)snprintf(json + used, cap - used, "],\"more\":%lu}",
                             (unsigned long)more);
    ret = wsg_web_answer(req->conn, MHD_HTTP_OK, "application/json", json,
                         used, 0);
    goto out;
out_oom:
    ret = wsg_web_error(req->conn, MHD_HTTP_INTERNAL_SERVER_ERROR,
                        "out of memory");
out:
    free(json);
    free(list);
    closedir(dir);
    return ret;
}

/* GET: the file as a download (the editor fetches it the same way). */
static enum MHD_Result file_get(struct wsg_web_req *req, int dfd,
                                const char *name)
{
    char why[256], disp[SCRIPT_NAME_MAX + 32];
    struct MHD_Response *r = NULL;
    enum MHD_Result ret;
    struct stat st;
    int fd;

    fd = openat(dfd, name, O_RDONLY | O_NOFOLLOW | O_NONBLOCK | O_CLOEXEC);
    if (fd < 0) {
        snprintf(why, sizeof why, "%s: %s", name, strerror(errno));
        if (errno == ENOENT)
            return wsg_web_error(req->conn, MHD_HTTP_NOT_FOUND, why);
        if (errno == ELOOP)
            snprintf(why, sizeof why, "%s is a symbolic link: not served",
                     name);
        return wsg_web_error(req->conn, MHD_HTTP_FORBIDDEN, why);
    }
    if (fstat(fd, &st) < 0 || !S_ISREG(st.st_mode)) {
        close(fd);
        snprintf(why, sizeof why, "%s is not a regular file", name);
        return wsg_web_error(req->conn, MHD_HTTP_FORBIDDEN, why);
    }
    /* MHD sends the file from its descriptor and closes it. */
    r = MHD_create_response_from_fd((uint64_t)st.st_size, fd);
    if (!r) {
        close(fd);
        return MHD_NO;
    }
    snprintf(disp, sizeof disp, "attachment; filename=\"%s\"", name);
    if (MHD_add_response_header(r, MHD_HTTP_HEADER_CONTENT_TYPE,
                                "text/x-lua; charset=utf-8") != MHD_YES ||
        MHD_add_response_header(r, MHD_HTTP_HEADER_CONTENT_DISPOSITION,
                                disp) != MHD_YES ||
        MHD_add_response_header(r, MHD_HTTP_HEADER_CACHE_CONTROL,
                                "no-store") != MHD_YES ||
        MHD_add_response_header(r, "X-Content-Type-Options", "nosniff") !=
            MHD_YES) {
        MHD_destroy_response(r);
        return MHD_NO;
    }
    ret = MHD_queue_response(req->conn, MHD_HTTP_OK, r);
    MHD_destroy_response(r);
    return ret;
}

/* The scripts of the directory (what the list shows) but name, which an
 * upload replaces: how many, and their bytes. 0 or -errno. */
static int dir_usage(int dfd, const char *name, unsigned long *count,
                     unsigned long long *bytes)
{
    char why[512]; /* file_stat's reason, with a name of up to 255 bytes */
    struct dirent *de;
    struct stat st;
    DIR *dir;
    int fd;

    *count = 0;
    *bytes = 0;
    /* A description of its own: reading it moves no offset of dfd's. */
    fd = openat(dfd, ".", O_RDONLY | O_DIRECTORY | O_CLOEXEC);
    if (fd < 0)
        return -errno;
    dir = fdopendir(fd);
    if (!dir) {
        int r = -errno;

        close(fd);
        return r;
    }
    while ((de = readdir(dir)) != NULL) {
        if (strcmp(de->d_name, name) == 0 ||
            name_check(de->d_name, why, sizeof why) < 0 ||
            file_stat(fd, de->d_name, &st, why, sizeof why) != 0)
            continue;
        (*count)++;
        *bytes += (unsigned long long)st.st_size;
    }
    closedir(dir);
    return 0;
}

/* An upload past the directory's bounds (--script-quota, --script-files):
 * 0, or the answer's status with the reason in why: 413 for a script
 * larger than the whole quota, 507 for one the directory has no room
 * left for. */
static unsigned quota_check(const struct wsg_options *o, int dfd,
                            const char *name, size_t len, char *why,
                            size_t cap)
{
    unsigned long long bytes;
    unsigned long count;
    int r;

    if (len > o->script_quota) {
        snprintf(why, cap,
                 "%s: %lu bytes are more than the script directory may hold "
                 "(%lu bytes, --script-quota)",
                 name, (unsigned long)len, (unsigned long)o->script_quota);
        return MHD_HTTP_CONTENT_TOO_LARGE;
    }
    r = dir_usage(dfd, name, &count, &bytes);
    if (r < 0) {
        snprintf(why, cap, "%s not saved: %s", name, strerror(-r));
        return MHD_HTTP_INTERNAL_SERVER_ERROR;
    }
    if (count + 1 > o->script_files) {
        snprintf(why, cap,
                 "%s not saved: the script directory holds %lu scripts, "
                 "at most %lu (--script-files): delete one first",
                 name, count, (unsigned long)o->script_files);
        return MHD_HTTP_INSUFFICIENT_STORAGE;
    }
    if (bytes + len > o->script_quota) {
        snprintf(why, cap,
                 "%s not saved: the scripts would take %llu bytes, at most "
                 "%lu (--script-quota): delete some first",
                 name, bytes + len, (unsigned long)o->script_quota);
        return MHD_HTTP_INSUFFICIENT_STORAGE;
    }
    return 0;
}

/* PUT: the body becomes the file, through a temporary file renamed over
 * it: 201 made, 200 replaced; within the directory's bounds. */
static enum MHD_Result file_put(const struct wsg_web *web,
                                struct wsg_web_req *req, int dfd,
                                const char *name)
{
    char why[256], tmp[SCRIPT_NAME_MAX + 8];
    struct stat st;
    unsigned status;
    int r, existed;

    status = file_stat(dfd, name, &st, why, sizeof why);
    if (status != 0 && status != MHD_HTTP_NOT_FOUND)
        return wsg_web_error(req->conn, status, why);
    existed = status == 0;
    status =
        quota_check(&web->d->opt, dfd, name, req->body_len, why, sizeof why);
    if (status != 0)
        return wsg_web_error(req->conn, status, why);
    /* Hidden: no script's name starts with a dot. */
    snprintf(tmp, sizeof tmp, ".%s.part", name);
    r = wsg_web_replace_file(dfd, name, tmp, req->body, req->body_len, NULL);
    if (r < 0)
        goto fail;
    return wsg_web_json(req->conn, existed ? MHD_HTTP_OK : MHD_HTTP_CREATED,
                        "{\"name\":\"%s\",\"size\":%lu,\"created\":%s}", name,
                        (unsigned long)req->body_len,
                        existed ? "false" : "true");
fail:
    snprintf(why, sizeof why, "%s not saved: %s", name, strerror(-r));
    return wsg_web_error(req->conn,
                         r == -ENOSPC || r == -EDQUOT
                             ? MHD_HTTP_INSUFFICIENT_STORAGE
                             : MHD_HTTP_INTERNAL_SERVER_ERROR,
                         why);
}

/* DELETE: the file (a running script keeps running: it was read at its
 * start). */
static enum MHD_Result file_delete(struct wsg_web_req *req, int dfd,
                                   const char *name)
{
    char why[256];
    struct stat st;
    unsigned status;

    status = file_stat(dfd, name, &st, why, sizeof why);
    if (status != 0)
        return wsg_web_error(req->conn, status, why);
    if (unlinkat(dfd, name, 0) < 0) {
        snprintf(why, sizeof why, "%s not deleted: %s", name, strerror(errno));
        return wsg_web_error(req->conn, MHD_HTTP_INTERNAL_SERVER_ERROR, why);
    }
    return wsg_web_json(req->conn, MHD_HTTP_OK, "{\"deleted\":\"%s\"}", name);
}

/* GET, PUT and DELETE /scripts/NAME. */
enum MHD_Result wsg_web_serve_script_file(struct wsg_web *web,
                                          struct wsg_web_req *req)
{
    const char *name = req->tail ? req->tail : "";
    enum MHD_Result ret;
    char why[256];
    int dfd;

    /* The name first: a bad one is the client's error whatever the
     * server's setup. */
    if (name_check(name, why, sizeof why) < 0)
        return wsg_web_error(req->conn, MHD_HTTP_BAD_REQUEST, why);
    dfd = dir_open(web);
    if (dfd < 0)
        return dir_error(web, req->conn, dfd);
    if (req->method == WSG_WEB_PUT)
        ret = file_put(web, req, dfd, name);
    else if (req->method == WSG_WEB_DELETE)
        ret = file_delete(req, dfd, name);
    else
        ret = file_get(req, dfd, name);
    close(dfd);
    return ret;
}

unsigned wsg_web_script_start(struct wsg_web *web, struct wsg_script *h,
                              const char *name, char *why, size_t cap)
{
    char path[PATH_MAX];
    int dfd, fd, r;

    if (name_check(name, why, cap) < 0)
        return MHD_HTTP_BAD_REQUEST;
    dfd = dir_open(web);
    if (dfd < 0) {
        if (dfd == -ENXIO)
            snprintf(why, cap,
                     "no script directory: start wsgemu with --script-dir "
                     "DIR");
        else
            snprintf(why, cap, "script directory %s: %s",
                     web->d->opt.script_dir, strerror(-dfd));
        return MHD_HTTP_CONFLICT;
    }
    /* Checked and opened in one step, relative to the directory and not
     * following a link: what runs is what was opened, whatever is put in
     * the name's place afterwards. */
    fd = wsg_script_open_at(dfd, name);
    close(dfd);
    if (fd < 0) {
        snprintf(why, cap, "%s: %s%s", name, wsg_script_open_strerror(fd),
                 fd == -ELOOP || fd == -ENOEXEC
                     ? " of the script directory: not run"
                     : "");
        return fd == -ENOENT ? MHD_HTTP_NOT_FOUND
               : fd == -ELOOP || fd == -ENOEXEC || fd == -EACCES
                   ? MHD_HTTP_FORBIDDEN
                   : MHD_HTTP_INTERNAL_SERVER_ERROR;
    }
    if ((size_t)snprintf(path, sizeof path, "%s/%s", web->d->opt.script_dir,
                         name) >= sizeof path) {
        close(fd);
        snprintf(why, cap, "the script's path is too long");
        return MHD_HTTP_INTERNAL_SERVER_ERROR;
    }
    r = wsg_script_start_fd(h, fd, path, why, cap);
    close(fd);
    if (r == -EBUSY) {
        snprintf(why, cap, "a script runs already: stop it first");
        return MHD_HTTP_CONFLICT;
    }
    /* It failed as it started (does not compile, or an error before it
     * first waits): D20 is set, its error in the state. */
    if (r < 0)
        return r == -EINVAL ? HTTP_UNPROCESSABLE
                            : MHD_HTTP_INTERNAL_SERVER_ERROR;
    return 0;
}

/* POST /script/run, name=NAME: the script host runs DIR/NAME. */
static enum MHD_Result script_run(struct wsg_web *web, struct wsg_web_req *req)
{
    const char *name = wsg_web_field(req, "name");
    struct wsg_script *h;
    unsigned status;
    char why[512];

    if (!name)
        return wsg_web_error(req->conn, MHD_HTTP_BAD_REQUEST,
                             "no script: post name=NAME.lua");
    if (wsg_gripper_script(web->g, &h) < 0)
        return wsg_web_error(req->conn, MHD_HTTP_INTERNAL_SERVER_ERROR,
                             "no memory for a script host");
    wsg_web_touch(web);
    status = wsg_web_script_start(web, h, name, why, sizeof why);
    wsg_web_done(web);
    if (status != 0)
        return wsg_web_error(req->conn, status, why);
    return wsg_web_json(req->conn, MHD_HTTP_OK,
                        "{\"ok\":true,\"running\":\"%s\"}", name);
}

/* GET /script/status: the state's "script" object with what does not
 * fit there: the whole error, the host's state and memory. Always
 * answered: the name and the error are escaped into rooms that together
 * fit the answer, each cut at a whole character when longer. */
static enum MHD_Result script_status(struct wsg_web *web,
                                     struct wsg_web_req *req)
{
    char name[STATUS_NAME_MAX], error[STATUS_ERROR_MAX];
    char out[STATUS_NAME_MAX + STATUS_ERROR_MAX + 192];
    struct wsg_script_status st;
    struct wsg_script *h;
    const char *base;
    int n;

    if (wsg_gripper_script(web->g, &h) < 0)
        return wsg_web_error(req->conn, MHD_HTTP_INTERNAL_SERVER_ERROR,
                             "no memory for a script host");
    wsg_web_touch(web);
    wsg_script_status(h, &st);
    wsg_web_done(web);
    base = st.file ? strrchr(st.file, '/') : NULL;
    base = base ? base + 1 : st.file;
    if (base)
        wsg_web_escape(name, sizeof name, base, strlen(base));
    if (st.error)
        wsg_web_escape(error, sizeof error, st.error, strlen(st.error));
    n = snprintf(out, sizeof out,
                 "{\"name\":%s%s%s,\"running\":%s,\"failed\":%s,"
                 "\"error\":%s%s%s,\"memory\":%lu,\"memory_max\":%lu}",
                 base ? "\"" : "", base ? name : "null", base ? "\"" : "",
                 st.running ? "true" : "false", st.failed ? "true" : "false",
                 st.error ? "\"" : "", st.error ? error : "null",
                 st.error ? "\"" : "", (unsigned long)st.memory,
                 (unsigned long)st.memory_max);
    /* The rooms are sized so that it fits: this cannot fail. */
    if (n < 0 || (size_t)n >= sizeof out)
        return wsg_web_error(req->conn, MHD_HTTP_INTERNAL_SERVER_ERROR,
                             "the status does not fit the answer");
    return wsg_web_answer(req->conn, MHD_HTTP_OK, "application/json", out,
                          (size_t)n, 0);
}

/* GET /script/output?from=N: what the script printed from byte N on
 * (the page's console fills itself from it when opened, then follows
 * the log's "script print" lines). */
static enum MHD_Result script_output(struct wsg_web *web,
                                     struct wsg_web_req *req)
{
    const char *from_text = wsg_web_field(req, "from");
    char text[1024], esc[WSG_WEB_ANSWER_MAX - 128];
    unsigned long from = 0;
    struct wsg_script *h;
    uint64_t start, end;
    size_t n, took;

    if (from_text && wsg_parse_ulong(from_text, ULONG_MAX, &from) < 0)
        return wsg_web_error(req->conn, MHD_HTTP_BAD_REQUEST,
                             "from must be a byte offset");
    if (wsg_gripper_script(web->g, &h) < 0)
        return wsg_web_error(req->conn, MHD_HTTP_INTERNAL_SERVER_ERROR,
                             "no memory for a script host");
    start = wsg_script_output(h, from, text, sizeof text, &n, &end);
    /* Escaped in full, or cut: then only the bytes it holds count. A
     * character cut in two by the copy waits for the next read, whole
     * (one at the very end is sent as it is: nothing may ever follow). */
    took = start + n < end ? wsg_web_utf8_whole(text, n) : n;
    while (wsg_web_escape(esc, sizeof esc, text, took) == sizeof esc)
        took = wsg_web_utf8_whole(text, took / 2);
    return wsg_web_json(req->conn, MHD_HTTP_OK,
                        "{\"from\":%llu,\"text\":\"%s\",\"next\":%llu,"
                        "\"end\":%llu}",
                        (unsigned long long)start, esc,
                        (unsigned long long)(start + took),
                        (unsigned long long)end);
}

/* POST /script/run and /script/stop; GET /script/status and
 * /script/output. */
enum MHD_Result wsg_web_serve_script_run(struct wsg_web *web,
                                         struct wsg_web_req *req)
{
    const char *verb = req->tail ? req->tail : "";
    struct wsg_script *h;
    int r;

    if (req->method == WSG_WEB_GET && strcmp(verb, "status") == 0)
        return script_status(web, req);
    if (req->method == WSG_WEB_GET && strcmp(verb, "output") == 0)
        return script_output(web, req);
    if (req->method == WSG_WEB_POST && strcmp(verb, "run") == 0)
        return script_run(web, req);
    if (req->method == WSG_WEB_POST && strcmp(verb, "stop") == 0) {
        if (wsg_gripper_script(web->g, &h) < 0)
            return wsg_web_error(req->conn, MHD_HTTP_INTERNAL_SERVER_ERROR,
                                 "no memory for a script host");
        wsg_web_touch(web);
        r = wsg_script_stop(h);
        wsg_web_done(web);
        return wsg_web_json(req->conn, MHD_HTTP_OK,
                            "{\"ok\":true,\"stopped\":%s}",
                            r < 0 ? "false" : "true");
    }
    return wsg_web_error(req->conn, MHD_HTTP_NOT_FOUND,
                         "POST /script/run (name=NAME.lua) or /script/stop; "
                         "GET /script/status or /script/output?from=N");
}
