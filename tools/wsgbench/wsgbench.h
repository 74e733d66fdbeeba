/*
 * What the files of wsgbench share: its bounds and constants, the
 * options, the servers, the connections, the rows of the table, the
 * bench's state, the globals of the signal handler, and the functions one
 * file offers the others (grouped by the file that defines them, where
 * each is described).
 */
#ifndef WSG_TOOLS_WSGBENCH_H
#define WSG_TOOLS_WSGBENCH_H

#include <limits.h>
#include <math.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <sys/types.h>

#include "ctljson.h"
#include "wsg/proto.h"
#include "wsgclient.h"

#ifndef WSG_VERSION
#define WSG_VERSION "?"
#endif

#define REPLY_MS    2000  /* an immediate reply */
#define READY_MS    10000 /* a server's ready line */
#define FLEET_MS    60000 /* a fleet's ready line, all its homings */
#define MOTION_MS   30000 /* a motion's final result */
#define STALL_MS    1000  /* a 10 ms stream silent this long is broken */
#define STREAM_MS   10    /* the jitter stream's period */
#define ROUNDS      10    /* latency: alternating rounds */
#define STROKE_MM   110.0 /* WSG 50 */
#define NS_PER_S    1000000000ull
#define NS_PER_MS   1000000ull
#define ROWS_MAX    96
#define NOT_APPLIED (-INFINITY) /* a row's reference: not applicable */
#define EMU         0
#define REF         1

enum link_kind { L_TCP, L_UDP, L_PTY };
extern const char *const kind_name[]; /* links.c: "TCP", "UDP", "pty" */

struct opts {
    const char *emu, *ref;
    const char *attach; /* a running emulator's ready line, or NULL */
    long pid;           /* its process, or -1 */
    long samples;
    long inflight;
    double tput_s, jitter_s, idle_s, move_s;
    long fleet;
    int quick;
    const char *scripts; /* where bench_echo.lua and bench_pd.lua are */
    double script_s;     /* each rate of the PD script */
    int no_script;
    int no_gcl;
    int no_web;
};

struct server {
    const char *name;
    pid_t pid;
    int out_fd;
    char *line; /* the ready line, without its newline */
};

/* One client connection, named for messages. */
struct link {
    struct wsg_client c;
    char who[32]; /* "wsgemu TCP" */
};

enum target { T_NONE, T_LT, T_LE, T_GE, T_EQ, T_NEAR };

struct row {
    char label[48];
    double emu, ref; /* NAN: not measured; ref NOT_APPLIED */
    int decimals;
    enum target tk;
    double tv, tol; /* T_NEAR: within tv +- tol */
    int on_ratio;   /* the target applies to emu/ref */
    char ttext[20];
};

struct proc_sample {
    uint64_t t_ns;
    unsigned long long ctxt, cpu_ns;
};

struct bench {
    struct opts o;
    int cpu_bench, cpu_server; /* -1: not pinned */
    int ncpu;
    char emu_exe[PATH_MAX], ref_exe[PATH_MAX];
    char tmpdir[64], pty_path[2][PATH_MAX];
    int udp_rfd[2];
    uint16_t udp_remote[2];
    struct server srv[2]; /* attached: srv[EMU] has only its line */
    pid_t pid[2];         /* whose /proc the rows read; -1: none */
    int attach;
    struct row rows[ROWS_MAX];
    int nrows;
    int failures;
};

struct dist {
    double p50, p99, max;
};

/* The servers running now and the bench's temporary directory, for the
 * SIGINT/SIGTERM handler (servers.c); while an attached emulator runs at
 * x100, its control channel and the command that puts its time scale
 * back (motion.c sets them). */
#define LIVE_MAX 4
extern volatile pid_t live[LIVE_MAX];
extern char live_dir[64];
extern volatile int live_ctl;
extern char live_restore[48];
extern volatile size_t live_restore_len;

/* 43h with no parameters (links.c), encoded once by main. */
extern uint8_t req_width[WSG_HEADER_LEN + WSG_CRC_LEN];

struct sockaddr_in;

/* ---- messages and the clock (main.c) ---- */

void msg(const char *fmt, ...);
uint64_t now_ns(void);
void sleep_s(double s);

/* ---- statistics, rows and the table (table.c) ---- */

struct dist dist_of(double *v, size_t n);
/* Two kinds of sample (sides 0 and 1) taken in ROUNDS alternating rounds
 * of --samples/ROUNDS each, after a warm-up of both, so that the machine's
 * noise hits both alike: take(ctx, side, &us) takes one (0, or -1
 * reported); turn(ctx, side, 1) before a side's round and (ctx, side, 0)
 * after it, if not NULL. Their distributions into dd (NaN when it failed).
 * 0, or -1. */
int alternate(struct bench *b, int (*take)(void *ctx, int side, double *us),
              int (*turn)(void *ctx, int side, int on), void *ctx,
              struct dist dd[2]);
struct row *add_row(struct bench *b, const char *label, double emu, double ref,
                    int decimals);
void set_target(struct row *r, enum target tk, double tv, int on_ratio,
                const char *text);
void print_table(const struct bench *b);

/* ---- servers, ready lines, /proc (servers.c) ---- */

void on_signal(int sig);
void pin(int cpu);
int server_start(struct bench *b, struct server *s, const char *name,
                 char *const *argv, int timeout_ms);
int server_stop(struct server *s);
char *field(const char *line, const char *name);
int parse_ipport(const char *s, struct sockaddr_in *sa);
int link_ready(struct link *l, const char *line, const char *key);
/* A wsgemu of a bench's own with a TCP connection and its control
 * channel (the finger and script rows). */
struct emud {
    struct server s;
    struct link l, ctl;
    int started;
};
void emud_init(struct emud *d, const char *name);
int emud_start(struct bench *b, struct emud *d, const char *name, char **argv);
int emud_stop(struct emud *d);
int attach_lacks(const struct bench *b, const char *key, const char *rows);
int attach_nopid(const struct bench *b, const char *what);
int proc_read(pid_t pid, struct proc_sample *s);
double wakes_per_s(const struct proc_sample *a, const struct proc_sample *b);
double cpu_percent(const struct proc_sample *a, const struct proc_sample *b);
double proc_mib(pid_t pid, const char *key);

/* ---- connections and the 43h request (links.c) ---- */

void link_init(struct link *l, enum link_kind kind, const char *name);
int link_tcp(struct link *l, const struct sockaddr_in *sa);
int link_send(struct link *l, const uint8_t *buf, size_t n);
int link_sendf(struct link *l, uint8_t id, const uint8_t *payload, size_t len);
int link_read(struct link *l);
int link_wait(struct link *l, uint64_t deadline);
int link_recv(struct link *l, struct wsg_client_frame *f, uint64_t deadline);
int link_recv_id(struct link *l, uint8_t id, struct wsg_client_frame *f,
                 int timeout_ms);
int link_motion(struct link *l, uint8_t id, const uint8_t *payload,
                size_t len);
void link_close(struct link *l);
int ctl_cmd(struct link *l, const char *cmd, char *out, size_t cap);
int ctl_stats(struct link *ctl, double *steps, double *overruns);
int ctl_time(struct link *ctl, double *sim, uint64_t *wall);
int check_width(const struct link *l, const struct wsg_client_frame *f);
int open_link(struct bench *b, struct link *l, int which, enum link_kind kind);
int sample(struct link *l, double *us);

/* ---- latency, throughput, jitter (traffic.c) ---- */

int bench_latency(struct bench *b, enum link_kind kind);
int bench_throughput(struct bench *b);
int bench_jitter(struct bench *b);

/* ---- idle and memory (idle.c) ---- */

int bench_idle(struct bench *b);
int bench_slow_stream(struct bench *b);
int bench_memory(struct bench *b);

/* ---- moving and time scale (motion.c) ---- */

int measure_moving(struct link *ctl, pid_t pid, double secs, double *rate,
                   double *overruns, double *cpu);
void put_move(uint8_t *pl, double width, double speed);
double slow_speed(double window_s);
int bench_moving(struct bench *b);
int bench_timescale(struct bench *b);

/* ---- the MuJoCo plant (physics.c) ---- */

int bench_physics(struct bench *b);
/* fingers.c */
int bench_fingers(struct bench *b);

/* ---- the fleet (fleet.c) ---- */

int bench_fleet(struct bench *b);

/* ---- scripts on the gripper (script.c) ---- */

int bench_script(struct bench *b);

/* ---- GCL, the text interface (gcl.c) ---- */

int bench_gcl(struct bench *b);

/* ---- the web page: 43h with a page watching (web.c) ---- */

int bench_web(struct bench *b);

#endif
