/*
 * What the files of wsgctl share: its exit statuses, the options, the link
 * to the gripper, the context a command runs in, and the functions one
 * file offers the others (grouped by the file that defines them, where
 * each is described).
 */
#ifndef WSG_TOOLS_WSGCTL_H
#define WSG_TOOLS_WSGCTL_H

#include <signal.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>

#include "ctljson.h"
#include "wsg/device.h"
#include "wsg/proto.h"
#include "wsgclient.h"

/* Exit statuses (documented in usage()). */
#define EXIT_OK          0
#define EXIT_GRIPPER     1 /* the gripper answered an error status */
#define EXIT_USAGE       2
#define EXIT_CONN        3 /* cannot connect, I/O error, no answer in time */
#define EXIT_INTERRUPTED 130

#define DEFAULT_HOST     "127.0.0.1" /* without --tcp and WSG_HOST */
#define DEFAULT_PORT     1000        /* without --tcp and WSG_PORT */
#define DEFAULT_UDP_PORT 1501 /* where the gripper sends its UDP answers */

/* Set by SIGINT/SIGTERM (main.c); a flag, since the handler may do
 * nothing else. The link's waits end when it is raised. */
extern volatile sig_atomic_t interrupted;

/* LINK_CONTROL: the emulator's control channel, read only (see
 * control_read). */
enum link_kind { LINK_TCP, LINK_UDP, LINK_SERIAL, LINK_CONTROL };

/* --json: the object of the command running, gathered as it runs
 * (json.c). */
struct jout {
    char body[72 * 1024]; /* its fields, each with a leading comma; room
                           * for a script's output (64 KiB kept) */
    size_t len;
    int cut;        /* a field did not fit */
    int gripper;    /* the gripper was asked: "status" on success */
    int has_status; /* the gripper answered with status */
    int streamed;   /* watch printed an object a value already */
    unsigned status;
};

struct opts {
    enum link_kind kind;
    const char *addr;
    int addr_given; /* --tcp, --udp, --serial or --control on the line */
    double timeout_s;
    int quiet;
    int relative;
    int stop_on_block;
    int reset;
    long count; /* watch: stop after this many values; 0: until SIGINT */
    int text;   /* --text: GCL lines instead of binary packets (text.c) */
    int has_force;
    double force; /* --force N: GCL's GRIP(force, ...) */
    int probe;    /* wait-ready: a failure to connect is retried, unsaid */
    unsigned long step_ms;    /* --step: simulated ms after E_CMD_PENDING */
    const char *step_control; /* --step: the control channel (WSG_CONTROL) */
    struct jout *jo;          /* --json: where the values go; NULL without */
};

/* The link to the gripper, and whether its close was announced. */
struct conn {
    enum link_kind kind;
    struct wsg_client l;
    int announced; /* TCP: 07h (GCL: BYE()) sent, no second one */
    int text;      /* GCL: closed with BYE() (text_close) */
    int heard;     /* GCL: a line came back */
};

struct ctx {
    struct opts o;
    struct conn c;
    int have_conn;
    const char *command; /* wsgctl's name of the command running */
};

/* Where a command can go: the gripper's interface only (the default, 0),
 * also through the emulator's control channel (readings it holds), or
 * only there (the channel's scenario commands and scripts). */
enum via { VIA_GRIPPER, VIA_BOTH, VIA_CONTROL };

/* A command of wsgctl: its runner, how many positional arguments, whether
 * it needs the link, its usage lines, and where it can go. */
struct command {
    const char *name;
    int (*run)(struct ctx *x, int argc, char **argv);
    int min, max;     /* positional arguments */
    int conn;         /* needs the link */
    const char *args; /* for usage */
    const char *what;
    const char *example;
    enum via via;
};

typedef void (*pending_fn)(const struct opts *o,
                           const struct wsg_client_frame *r);

/* ---- options and their arguments; messages (main.c) ---- */

void err(const char *fmt, ...);
/* What err() said last, without "wsgctl: " ("" if nothing): --json's
 * "error". */
const char *err_last(void);
int parse_float(const char *s, float *v);
int parse_ulong(const char *s, unsigned long max, unsigned long *v);
int split_addr(const char *addr, char *host, size_t cap, unsigned long *port,
               unsigned long *local);

/* ---- the link (link.c) ---- */

int conn_open(struct conn *c, const struct opts *o);
int conn_send(struct conn *c, uint8_t id, const uint8_t *payload, size_t len);
int conn_recv(struct conn *c, struct wsg_client_frame *r, uint64_t deadline);
int recv_fail(int rc, uint8_t id, const struct opts *o);
uint64_t timeout_deadline(const struct opts *o);
int xact(struct ctx *x, uint8_t id, const uint8_t *payload, size_t len,
         struct wsg_client_frame *r, pending_fn on_pending);
void conn_close(struct conn *c);

/* ---- commands (commands.c) ---- */

int c_home(struct ctx *x, int argc, char **argv);
int c_move(struct ctx *x, int argc, char **argv);
int c_grasp(struct ctx *x, int argc, char **argv);
int c_release(struct ctx *x, int argc, char **argv);
int c_stop(struct ctx *x, int argc, char **argv);
int c_fast_stop(struct ctx *x, int argc, char **argv);
int c_ack(struct ctx *x, int argc, char **argv);
int c_info(struct ctx *x, int argc, char **argv);
int c_finger(struct ctx *x, int argc, char **argv);
int c_limits(struct ctx *x, int argc, char **argv);
int c_state(struct ctx *x, int argc, char **argv);
int c_width(struct ctx *x, int argc, char **argv);
int c_speed(struct ctx *x, int argc, char **argv);
int c_force(struct ctx *x, int argc, char **argv);
int c_temperature(struct ctx *x, int argc, char **argv);
int c_tag(struct ctx *x, int argc, char **argv);
int c_acc(struct ctx *x, int argc, char **argv);
int c_force_limit(struct ctx *x, int argc, char **argv);
int c_soft_limits(struct ctx *x, int argc, char **argv);
int c_overdrive(struct ctx *x, int argc, char **argv);
int c_stats(struct ctx *x, int argc, char **argv);
int c_loop(struct ctx *x, int argc, char **argv);
int c_tare(struct ctx *x, int argc, char **argv);
int c_bye(struct ctx *x, int argc, char **argv);
int c_raw(struct ctx *x, int argc, char **argv);

/* ---- watch (watch.c) ---- */

int c_watch(struct ctx *x, int argc, char **argv);

/* ---- printing what the gripper says; decode (decode.c) ---- */

int print_values(const struct opts *o, const char *indent, uint8_t id,
                 const uint8_t *p, size_t n);
void print_hex(const uint8_t *p, size_t n);
const char *cmd_name(uint8_t id);
int gripper_error(uint8_t id, unsigned status);
int c_decode(struct ctx *x, int argc, char **argv);

/* ---- the control channel (control.c) ---- */

int control_read(struct ctx *x, uint8_t id, const uint8_t *payload,
                 size_t len);
int control_line(struct ctx *x, const char *cmd, char *line, size_t cap,
                 const char **rest);
int c_channel(struct ctx *x, int argc, char **argv);

/* ---- waiting for the gripper (ready.c) ---- */

int c_wait_ready(struct ctx *x, int argc, char **argv);

/* ---- --json (json.c) ---- */

void jout_add(struct jout *j, const char *fmt, ...);
void jout_str(struct jout *j, const char *key, const char *s, size_t n);
void jout_value(struct jout *j, const struct wsg_value *v);
void jout_print(const struct jout *j, const char *command, int rc,
                const char *error);
void json_write_str(FILE *f, const char *s, size_t n);

/* ---- GCL, the text interface (text.c) ---- */

/* The commands with --text, and raw-text (which implies it). */
extern const struct command text_commands[];
extern const size_t text_ncommands;
void text_close(struct conn *c);
void close_both_ways(struct conn *c);

/* ---- scripts on the gripper, through the control channel (script.c) ---- */

int c_script(struct ctx *x, int argc, char **argv);
/* capture [start FILE | stop]: the control channel's capture, FILE made
 * absolute (control.c). */
int c_capture(struct ctx *x, int argc, char **argv);
/* FILE as the daemon gets it: absolute, since the daemon resolves a
 * relative path from its own working directory, not from wsgctl's. 0
 * with it in path; EXIT_USAGE (said) for a blank in it or one too long.
 * what names the command in the message. */
int wsgctl_path(const char *what, const char *file, char *path, size_t cap);

#endif
