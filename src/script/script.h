/*
 * The script host: a Lua 5.2 interpreter that runs one user script on a
 * gripper, as the WSG firmware runs the scripts in /user. The script registers
 * command IDs (cmd.register) whose packets the device then hands here
 * instead of answering E_CMD_UNKNOWN, reads them (cmd.read), answers them
 * (cmd.send) and drives the fingers (mc.*, grasping.*).
 *
 * The script runs as a coroutine inside the daemon's loop, without threads.
 * It runs until it waits (cmd.read with nothing queued, sleep) or until
 * its slice of steps is used up (instructions, and the work of library
 * functions: a long pattern match, a long move, yields across the call);
 * then it yields and the host keeps
 * what it waits for:
 *   - a packet: delivered from the device's hook as it arrives, and the
 *     script resumed at once, so an answer leaves in the same batch;
 *   - a time: simulated time (the model's), resumed by wsg_script_poll,
 *     which the owner calls after the model steps; wsg_script_next tells
 *     the owner when, so nothing wakes for a waiting script;
 *   - the processor: a preempted script asks the owner through the wake
 *     callback to call wsg_script_run again once other work is served.
 * With time paused, a waiting script resumes only when time is stepped or
 * a packet arrives: a test in lockstep sees the same thing on every run.
 *
 * The script is user code (uploads, later, from the web page): it gets no
 * io, os.execute, loadlib or debug, loads text chunks only, requires only
 * from its own directory, and its memory is capped. Its errors end it (D20)
 * and nothing it does ends the daemon. The host reads no clock but the
 * model's, and does no I/O but reading the script and its modules.
 */
#ifndef WSG_SCRIPT_H
#define WSG_SCRIPT_H

#include <stddef.h>
#include <stdint.h>

#include "wsg/device.h"

/* Default memory cap of a script (--script-memory). */
#define WSG_SCRIPT_MEMORY_DEFAULT (16u << 20)
/* Steps a script runs before it is preempted (an instruction is one, a
 * library function counts its work in them): a millisecond or less on
 * these machines, so every interface keeps answering. */
#define WSG_SCRIPT_SLICE 100000u
/* Packets for the script that wait to be read; one more is answered
 * E_OVERRUN, as the firmware answers a queue that is full. */
#define WSG_SCRIPT_QUEUE 64u
/* What the script printed that is kept for `script output`. */
#define WSG_SCRIPT_OUTPUT_MAX 65536u
/* cmd.send's largest payload: what the SIZE field can say. */
#define WSG_SCRIPT_SEND_MAX 65535u

struct wsg_script_config {
    size_t memory_max; /* bytes; 0: WSG_SCRIPT_MEMORY_DEFAULT */
    /* What the script prints (print, printf, and its error when it
     * fails), as it prints it; NULL: kept for wsg_script_output only. */
    void (*print)(void *ctx, const char *text, size_t len);
    /* The script was preempted: call wsg_script_run soon, after serving
     * what else is ready. Required. */
    void (*wake)(void *ctx);
    void *ctx;
    /* The script directory (--script-dir); NULL: none. A script outside
     * it (and its modules) may be any file the daemon can read: a compile
     * error then names its line and Lua's words, never its text. */
    const char *script_dir;
};

enum wsg_script_state {
    WSG_SCRIPT_STOPPED = 0, /* no script, or it ended */
    WSG_SCRIPT_RUNNING,     /* inside the interpreter right now */
    WSG_SCRIPT_RUNNABLE,    /* preempted: wants the processor */
    WSG_SCRIPT_READING,     /* in cmd.read, nothing queued */
    WSG_SCRIPT_SLEEPING     /* in sleep, until a simulated time */
};

struct wsg_script_status {
    enum wsg_script_state state;
    int running;       /* started and not ended */
    int failed;        /* ended with an error (D20) */
    const char *error; /* the error's message; NULL: none */
    const char *file;  /* the script's path; NULL: none run yet */
    size_t memory, memory_max;
    uint64_t wake_us;   /* SLEEPING: until this simulated time */
    uint64_t preempted; /* times it was preempted */
};

struct wsg_script;

/* A host for d's scripts; it installs itself as d's user_cmd. Returns 0 or
 * -ENOMEM. */
int wsg_script_new(struct wsg_script **out, struct wsg_device *d,
                   const struct wsg_script_config *cfg);
/* Stop the script and free the host; d's hook is removed. Safe on NULL. */
void wsg_script_free(struct wsg_script *h);

/* Run the script in file path: it starts at once and runs until it first
 * waits. The file is opened as wsg_script_open opens it. -EBUSY while one
 * runs (one at a time, as on the gripper); -errno when the file cannot be
 * opened or read (wsg_script_open's); -EINVAL when it does not compile or
 * fails before it first waits (it has failed then: D20, the error kept).
 * A reason goes to err either way. */
int wsg_script_start(struct wsg_script *h, const char *path, char *err,
                     size_t errlen);
/* The same with the script read from fd, an open regular file (the
 * caller keeps and closes it), named file (its modules are found in
 * file's directory): what was opened is what runs, with no path looked up
 * again between a check and the run. */
int wsg_script_start_fd(struct wsg_script *h, int fd, const char *file,
                        char *err, size_t errlen);
/* Open a script's file for reading the way wsg_script_start does: path's
 * directory resolved (realpath), the file opened relative to it in one
 * step without following a symbolic link (O_NOFOLLOW), and only a regular
 * file kept (a FIFO does not block the open). Returns the descriptor, or
 * -errno: -ELOOP for a link, -ENOEXEC for what is not a regular file.
 * file (if not NULL) gets the resolved path, DIR/NAME. */
int wsg_script_open(const char *path, char *file, size_t cap);
/* The same for name relative to the directory open as dfd. */
int wsg_script_open_at(int dfd, const char *name);
/* Words for wsg_script_open's -errno ("a symbolic link (not followed)",
 * "not a regular file", else strerror's). */
const char *wsg_script_open_strerror(int r);
/* End the running script: its IDs are unregistered, a speed-mode motion
 * it left running is stopped. 0, or -ESRCH when none runs. */
int wsg_script_stop(struct wsg_script *h);
void wsg_script_status(const struct wsg_script *h,
                       struct wsg_script_status *st);
/* IDs the script registered, into ids (up to cap); returns how many. */
size_t wsg_script_registered(const struct wsg_script *h, uint8_t *ids,
                             size_t cap);
/* What the script printed, from byte offset from of everything it printed
 * since the host was made: up to cap bytes into buf, their count in *n.
 * Returns the offset the copy started at (from, or the oldest byte kept
 * when from is older); *end is the offset after the last byte printed. */
uint64_t wsg_script_output(const struct wsg_script *h, uint64_t from,
                           char *buf, size_t cap, size_t *n, uint64_t *end);

/* The simulated time (us) at which a sleeping script wakes; UINT64_MAX
 * when it waits for no time. */
uint64_t wsg_script_next(const struct wsg_script *h);
/* After the model stepped: resume a script whose sleep is over. */
void wsg_script_poll(struct wsg_script *h);
/* Resume a preempted script for one slice (after the wake callback). */
void wsg_script_run(struct wsg_script *h);

/* cmd.send's flattening (flatten.c), apart for the fuzzer: the values on
 * L's stack from index first to the top, in order, into out: a number in
 * 0..255 is a byte, a boolean 0 or 1, a string its bytes, a table its
 * elements 1..#t (raw, no metamethods), nested at most
 * WSG_SCRIPT_NEST_MAX deep, visiting at most WSG_SCRIPT_SEND_VISITS
 * values (each argument and each element, a table repeated counted each
 * time). Returns the bytes written, or -1 with the reason in err (a
 * number out of range, another type, too deep, too many values, more than
 * cap bytes). The values it visited go to *visits (unless NULL). It never
 * raises a Lua error. */
#define WSG_SCRIPT_NEST_MAX 5
/* Twice a payload of single bytes, each in a table of its own: 2^17
 * values, a millisecond or two. */
#define WSG_SCRIPT_SEND_VISITS (1ul << 17)
struct lua_State;
long wsg_script_flatten(struct lua_State *L, int first, uint8_t *out,
                        size_t cap, char *err, size_t errlen, size_t *visits);

#endif
