/*
 * Lua's patterns (string.find, match, gmatch, gsub) as a machine whose
 * whole state is this struct, not the C stack: it runs for the steps it
 * is given and stops, and goes on from there when it is run again. The
 * string functions of a script (strlib.c) run it a slice at a time, so a
 * match that backtracks for hours is preempted like a loop in Lua is,
 * instead of holding the daemon inside one C call.
 *
 * The language and its errors are Lua 5.2's (lstrlib.c): the same
 * classes, sets, quantifiers, captures, %b, %f and back-references, the
 * same 32 captures, and the same depth of 200 nested choices ("pattern
 * too complex"). Errors come when the machine reaches the faulty item, as
 * in Lua. A step is bounded work: one pattern item at one position, a
 * byte of a %b scan or of an expansion, a byte of a set read once (sets
 * are read into a table of 256 bits and kept), 64 bytes of a
 * back-reference.
 */
#ifndef WSG_MATCH_H
#define WSG_MATCH_H

#include <stddef.h>
#include <stdint.h>

#define WSG_MATCH_CAPTURES 32
/* Choices open at once (Lua's MAXCCALLS, counting the match itself). */
#define WSG_MATCH_DEPTH 200
/* A capture's len while it is open, and for a position capture "()". */
#define WSG_MATCH_UNFINISHED (-1)
#define WSG_MATCH_POSITION   (-2)
/* Sets kept read, by where they are in the pattern. */
#define WSG_MATCH_SETS 8

enum wsg_match_result {
    WSG_MATCH_NO = 0, /* no match at this position */
    WSG_MATCH_YES,    /* a match, ending at m->end */
    WSG_MATCH_MORE,   /* the steps given are used up: run it again */
    WSG_MATCH_ERROR   /* a malformed pattern: m->error says why */
};

struct wsg_match_choice {
    unsigned char kind;
    int cap;        /* OPEN, CLOSE: the capture */
    const char *s;  /* OPT: where to go on; MAX: the first expansion;
                       MIN: where the shortest one ends */
    const char *p;  /* the item; OPT: where to go on */
    const char *ep; /* the item's end (its quantifier) */
    size_t n;       /* MAX: expansions still to try */
};

struct wsg_match_set {
    const char *p, *ep; /* the set's '[' and what follows its ']' */
    unsigned char bits[32];
};

/* No pointer in it points into it: a machine stopped in a C function's
 * frame can be copied into a userdata and run on from there. */

struct wsg_match {
    const char *src, *src_end; /* the subject */
    const char *pat, *p_end;   /* the pattern, after a '^' anchor */
    int level;                 /* captures open or closed */
    struct {
        const char *init;
        ptrdiff_t len; /* or WSG_MATCH_UNFINISHED, WSG_MATCH_POSITION */
    } cap[WSG_MATCH_CAPTURES];
    const char *end; /* YES: where the match ends */
    char error[48];  /* ERROR: why */
    /* The machine: what it does next, at s and p. */
    int mode;
    const char *s, *p;
    const char *ep;   /* an expansion's item end */
    const char *scan; /* a scan in progress (expansion, %b, %1) */
    size_t count;
    int ref;  /* %1: the capture */
    int set;  /* an expansion's set: its index in sets */
    int next; /* the entry of sets to replace next */
    int top;
    struct wsg_match_choice stack[WSG_MATCH_DEPTH];
    struct wsg_match_set sets[WSG_MATCH_SETS];
};

/* A match of pattern p (lp bytes, its '^' anchor removed: the caller
 * anchors) in the subject s (ls bytes). Both must stay where they are,
 * and be followed by a NUL, as Lua's strings are, while m is used. */
void wsg_match_init(struct wsg_match *m, const char *s, size_t ls,
                    const char *p, size_t lp);
/* Start a match at s (src <= s <= src_end): no captures, no choices. */
void wsg_match_at(struct wsg_match *m, const char *s);
/* Run for at most *steps steps, which are taken off *steps. */
enum wsg_match_result wsg_match_run(struct wsg_match *m, uint32_t *steps);

/* Steps that compare this many bytes at once (a back-reference, a plain
 * find's candidate). */
#define WSG_MATCH_BYTES_PER_STEP 64

#endif
