/*
 * Client library of the integration tests: starts the real wsgemu daemon as
 * a child process, reads its ready line, and talks to it over one of its
 * interfaces the way a driver would.
 *
 * A transport (struct emu_transport) is a small set of operations: open the
 * address named by a field of the ready line, send one packet, receive bytes
 * with a timeout, close. Everything above it (framing with the core's
 * wsg_parser, waiting for a given ID, request/reply) is shared, so the same
 * tests can run over every interface the daemon offers.
 *
 * Every wait takes a timeout: a daemon that never answers fails the test
 * instead of hanging it.
 */
#ifndef WSG_TEST_EMU_H
#define WSG_TEST_EMU_H

#include <stddef.h>
#include <stdint.h>
#include <sys/types.h>

#include "wsg/proto.h"
#include "wsgclient.h"

/* Every wait below is a failure bound, not an expectation: how long to
 * wait for what should come before calling it lost. A larger bound costs
 * nothing when things work, so the bounds are generous for a loaded 2-core
 * machine, and all of them are multiplied by one factor, emu_time_scale():
 * $WSG_TEST_TIME_SCALE when set (a number >= 1), else 10 when the programs
 * run under valgrind (WSG_TEST_WRAPPER names it; memcheck.sh), else 1.
 * What a test expects NOT to see within a window is scaled the same way, so
 * a slow daemon cannot make such a check pass by being late. Durations a
 * test measures are another matter: each says how it is judged. */
double emu_time_scale(void);
/* ms times emu_time_scale(), for the bound of a wait. The functions below
 * take their timeouts as given: callers scale them, with the constants
 * that follow or with emu_ms(). */
int emu_ms(int ms);

/* How long an immediate reply may take. NOTES: clients expect a reply
 * within 250 ms; this is far more, because a slow reply is not what these
 * waits are for: they only stop a hang. */
#define EMU_REPLY_MS emu_ms(5000)
/* The daemon prints its ready line within this time. */
#define EMU_READY_MS emu_ms(10000)
/* How long a daemon may take to exit after a signal (valgrind checks for
 * leaks then, which takes seconds). */
#define EMU_EXIT_MS emu_ms(5000)
/* A quiet window: how long "nothing arrives" is watched for. */
#define EMU_QUIET_MS emu_ms(300)
/* Homing from anywhere ends within 4 s of simulated time (NOTES), and a
 * preposition in these tests within 5 s; as bounds of real-time waits. */
#define EMU_HOMING_MS emu_ms(4000)
#define EMU_MOVE_MS   emu_ms(5000)

/* ---- the daemon process ---- */

struct emu_transport;

struct emu {
    pid_t pid;
    /* What a transport's daemon_args hook prepared: the arguments naming
     * the interface, and anything it reserved for its clients. */
    const char *tp_argv[8]; /* NULL-terminated */
    char tp_arg[4][160];
    int tp_fd;           /* -1 when unused */
    uint16_t tp_port;    /* e.g. UDP: where replies come back */
    unsigned tp_clients; /* clients opened so far */
    int out_fd;          /* read end of the daemon's stdout */
    char line[2048];     /* the ready line, without its newline */
    /* stdout after the ready line: what arrived with it, and at stop */
    char extra[1024];
    size_t extra_len;
};

/* Start exe with args (NULL-terminated, without argv[0]), stdout piped,
 * stderr shared with the test (so ctest shows the daemon's messages), and
 * wait up to EMU_READY_MS for the ready line. Returns 0, or -1 with a
 * message on stderr (the child is then reaped). */
int emu_start(struct emu *e, const char *exe, const char *const *args);
/* The two halves of emu_start, for a test that acts on the daemon while
 * it starts: emu_spawn starts it (0, or -1 with a message) and returns at
 * once; emu_ready waits up to EMU_READY_MS for its ready line (0, or -1
 * with a message: the child is then killed and reaped). */
int emu_spawn(struct emu *e, const char *exe, const char *const *args);
int emu_ready(struct emu *e);
/* Start with the interface of tp (its daemon_args) followed by extra
 * (NULL-terminated, may be NULL). Exits 77 when tp cannot run here. */
int emu_start_tp(struct emu *e, const char *exe,
                 const struct emu_transport *tp, const char *const *extra);
/* Start with several interfaces at once (each transport's daemon_args,
 * then extra); exits 77 when one cannot run here. */
int emu_start_multi(struct emu *e, const char *exe,
                    const struct emu_transport *const *tps, size_t ntp,
                    const char *const *extra);
/* The transport named by argv[2] ("tcp" when absent); exits 2 for an
 * unknown name. */
const struct emu_transport *emu_transport_arg(int argc, char **argv);
/* Send sig, wait up to EMU_EXIT_MS for the exit and collect the rest of
 * stdout into e->extra. Returns the exit status, 128+N if killed by signal N,
 * or -1 if it did not exit in time (it is then killed). */
int emu_stop_sig(struct emu *e, int sig);
int emu_stop(struct emu *e); /* SIGTERM */
/* Value of field name=... of the ready line into buf; NULL if absent. */
const char *emu_field(const struct emu *e, const char *name, char *buf,
                      size_t cap);

/* Run exe to its end (for option errors): stdout and stderr are captured
 * (NUL-terminated, truncated to their buffers). Returns the exit status as
 * emu_stop does, -1 if it ran longer than timeout_ms (it is then killed). */
int emu_run(const char *exe, const char *const *args, int timeout_ms,
            char *out, size_t outcap, char *err, size_t errcap);

/* ---- frames ---- */

/* Frames are the client library's (wsgclient.h): id, len, status and
 * payload. The parameters after the status: */
#define EMU_PARAMS(f)  WSG_CLIENT_PARAMS(f)
#define EMU_NPARAMS(f) WSG_CLIENT_NPARAMS(f)
/* When it was taken off the wire, on emu_now_ms()'s clock. */
#define EMU_T_MS(f) ((double)(f)->t_ns / 1e6)

/* Check that buf holds exactly one packet with a valid preamble, SIZE and
 * checksum (the CRC over all of it is 0) and decode it. Used for raw reads,
 * where the test wants the packet boundaries on the wire. Returns 0 or -1. */
int emu_packet_decode(const uint8_t *buf, size_t n,
                      struct wsg_client_frame *f);

/* ---- clients ---- */

struct emu_client;

struct emu_transport {
    const char *field; /* ready-line field with the address: "tcp" */
    int (*open)(struct emu_client *c, const char *addr);
    /* One packet, in one piece. 0 or -1. */
    int (*send)(struct emu_client *c, const uint8_t *pkt, size_t len);
    /* Wait up to timeout_ms for input and read what is there (one read).
     * Returns the byte count, 0 at the end of the stream, -1 on timeout,
     * -2 on an error. */
    long (*recv)(struct emu_client *c, uint8_t *buf, size_t cap,
                 int timeout_ms);
    /* abort: go away without an orderly shutdown (TCP: reset). */
    void (*close)(struct emu_client *c, int abort);
    /* Fill e->tp_argv with the options that start the daemon with this
     * interface on a free address. 0, or 77 when it cannot run here (the
     * reason printed), or -1. NULL: {"--FIELD", "127.0.0.1:0"}. */
    int (*daemon_args)(struct emu *e);
    /* Connection-oriented (TCP): 07h is available and a close without it
     * means FAST STOP. Otherwise 07h answers E_NOT_AVAILABLE. */
    int connection;
    /* One peer only (a serial line, a CAN bus): clients cannot be told
     * apart, so tests with several clients do not apply. */
    int single_peer;
};

extern const struct emu_transport emu_tcp;
extern const struct emu_transport emu_udp;
extern const struct emu_transport emu_can; /* emu_can.c */
extern const struct emu_transport emu_pty; /* emu_pty.c */
/* Every transport this library knows, NULL-terminated. */
extern const struct emu_transport *const emu_transports[];

/* Frames skipped by emu_recv_id are kept (the newest EMU_KEEP) so that a
 * reply that overtakes another one is not lost. */
#define EMU_KEEP 64

struct emu_client {
    const struct emu_transport *tp;
    struct emu *emu; /* the daemon it talks to */
    int fd;
    int fd2; /* a second socket where the transport needs one, else -1 */
    uint32_t tp_id; /* the transport's own: CAN command identifier */
    /* The receive side: the library's client over this transport's hooks.
     * link.seen[] counts good frames per ID since open, link.bad the
     * malformed ones, link.keep_n the frames kept, link.eof the end. */
    struct wsg_client link;
    struct wsg_client_frame keep[EMU_KEEP];
    uint16_t sync_token;
};

/* Connect over tp to the address the ready line gives. -1 (and a message)
 * if the field is absent or the connection fails. */
int emu_open(struct emu_client *c, struct emu *e,
             const struct emu_transport *tp);
/* The same to gripper n of a fleet (--grippers): the n-th of the field's
 * comma-separated values. */
int emu_open_nth(struct emu_client *c, struct emu *e,
                 const struct emu_transport *tp, unsigned n);
void emu_close(struct emu_client *c);
void emu_abort(struct emu_client *c);

int emu_send(struct emu_client *c, uint8_t id, const void *payload,
             size_t len);
int emu_send_raw(struct emu_client *c, const void *pkt, size_t len);
/* One read straight from the transport, bypassing the frame buffer (which
 * must be empty: use it on a connection that has only seen raw reads). */
long emu_recv_raw(struct emu_client *c, uint8_t *buf, size_t cap,
                  int timeout_ms);

/* Next frame in arrival order (kept ones first). 1: got one, 0: timeout,
 * -1: end of stream or error. */
int emu_recv(struct emu_client *c, struct wsg_client_frame *f, int timeout_ms);
/* Next frame with this ID; the others are kept. Same returns. */
int emu_recv_id(struct emu_client *c, uint8_t id, struct wsg_client_frame *f,
                int timeout_ms);
/* Forget the kept frames. */
void emu_drop_kept(struct emu_client *c);
/* Send and wait for the first frame with the same ID. Returns its status,
 * -1 on timeout or end of stream. f may be NULL. */
int emu_request(struct emu_client *c, uint8_t id, const void *payload,
                size_t len, struct wsg_client_frame *f, int timeout_ms);
/* Barrier: send a Loop (06h) with a fresh token and wait for its echo.
 * Every packet the daemon queued for this connection before it read the
 * Loop has then been parsed (and counted in seen[]). 0 or -1. */
int emu_sync(struct emu_client *c, int timeout_ms);

/* The whole file at path into buf (NUL-terminated, at most cap - 1
 * bytes): its length, or -1 when it cannot be opened. */
long emu_slurp(const char *path, char *buf, size_t cap);
/* A new temporary file (in $TMPDIR, else /tmp) named after tag, holding
 * text; path gets its name. Ends the test (exit 1) when it cannot be
 * written. */
void emu_temp_file(char *path, size_t cap, const char *tag, const char *text);

/* ---- gripper helpers (requests with an empty payload) ---- */

/* System state flags (40h); -1 on any failure, else 0. */
int emu_get_flags(struct emu_client *c, uint32_t *flags);
/* The grasping state (41h); -1 on any failure. */
int emu_get_grasp_state(struct emu_client *c);
/* A float reading (43h, 44h, 45h, 31h, 33h); 0 or -1. */
int emu_get_float(struct emu_client *c, uint8_t id, float *v);
/* Poll 40h until (flags & mask) == want. 0, or -1 on timeout; flags (if
 * not NULL) gets the last value read. */
int emu_wait_flags(struct emu_client *c, uint32_t mask, uint32_t want,
                   int timeout_ms, uint32_t *flags);
/* Poll a float reading (43h, 44h, 45h) until lo <= value <= hi. 0, or -1
 * on timeout; v (if not NULL) gets the last value read. */
int emu_wait_float(struct emu_client *c, uint8_t id, float lo, float hi,
                   int timeout_ms, float *v);
/* A motion command: the immediate reply into *immediate; when it is
 * E_CMD_PENDING, wait up to timeout_ms for the final result and return
 * it, else return the immediate status. -1 on timeout. */
int emu_motion(struct emu_client *c, uint8_t id, const void *payload,
               size_t len, int timeout_ms, int *immediate);
/* Send Homing, Preposition, Grasp and Release (valid parameters, one
 * each) and count the immediate answers that are not status. */
int emu_motions_answer(struct emu_client *c, int status);
/* Payload of Preposition (21h) / Grasp (25h) / Release (26h). */
size_t emu_move_payload(uint8_t *out, uint8_t flags, float width, float speed);
size_t emu_grasp_payload(uint8_t *out, float width, float speed);

/* Context switches (voluntary and not) and CPU ticks (user + system) of a
 * process so far, from /proc. 0 or -1. */
int emu_proc_activity(pid_t pid, long *switches, long *ticks);

/* Monotonic milliseconds. */
double emu_now_ms(void);
/* "A.B.C.D:PORT", as the ready line's fields give it, as an address. 0,
 * or -1 when it is not one. */
struct sockaddr_in;
int emu_ipv4_addr(const char *addr, struct sockaddr_in *sa);
void emu_sleep_ms(int ms);

/* Path of the daemon from argv[1]; test_skip-style exit 77 without it. */
const char *emu_exe(int argc, char **argv);

#endif
