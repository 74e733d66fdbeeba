/*
 * The pattern machine (match.h). Lua's own matcher (lstrlib.c) recurses:
 * each '?', '*', '+', '-' and capture is a C call that returns to try the
 * next choice when what follows fails. Here each of those is an entry on
 * a stack of choices, and failing is popping back to the newest one, so
 * the machine is a loop that can stop between any two steps. It tries
 * the same choices in the same order as Lua's, and so finds the same
 * match, with the same captures, and raises the same errors at the same
 * moments.
 *
 * The pattern language, its error messages and the order of the choices
 * are those of Lua's lstrlib.c, the same in Lua 5.2, which scripts run
 * on, and 5.4 (Copyright (C) 1994-2022 Lua.org, PUC-Rio, MIT licence).
 */
#include "match.h"

#include <ctype.h>
#include <stdio.h>
#include <string.h>

#define ESC '%'

enum { M_ITEM, M_FAIL, M_EXPAND, M_BALANCE, M_BACKREF };

/* What a choice undoes or tries when what follows it fails. */
enum {
    C_OPEN,  /* a capture opened: it goes */
    C_CLOSE, /* a capture closed: it is open again */
    C_OPT,   /* '?' matched: go on without it */
    C_MAX,   /* '*' or '+': one expansion less */
    C_MIN    /* '-': one expansion more */
};

/* The step's outcome inside the machine: go on, or one of the results. */
#define GO (-1)

static int error_at(struct wsg_match *m, const char *msg)
{
    snprintf(m->error, sizeof m->error, "%s", msg);
    return WSG_MATCH_ERROR;
}

static int class_match(int c, int cl)
{
    int res;

    switch (tolower(cl)) {
    case 'a':
        res = isalpha(c);
        break;
    case 'c':
        res = iscntrl(c);
        break;
    case 'd':
        res = isdigit(c);
        break;
    case 'g':
        res = isgraph(c);
        break;
    case 'l':
        res = islower(c);
        break;
    case 'p':
        res = ispunct(c);
        break;
    case 's':
        res = isspace(c);
        break;
    case 'u':
        res = isupper(c);
        break;
    case 'w':
        res = isalnum(c);
        break;
    case 'x':
        res = isxdigit(c);
        break;
    case 'z':
        res = c == 0;
        break;
    default:
        return cl == c;
    }
    return islower(cl) ? res != 0 : res == 0;
}

static void bits_set(unsigned char *bits, int c)
{
    bits[c >> 3] |= (unsigned char)(1u << (c & 7));
}

static int bits_has(const unsigned char *bits, int c)
{
    return bits[c >> 3] >> (c & 7) & 1;
}

/* The set at p ('['): found among those read, or read now, at the cost
 * of its length in steps (and 256 for each class in it). Its index in
 * m->sets, or -1 with the error set. */
static int set_get(struct wsg_match *m, const char *p, uint32_t *steps)
{
    struct wsg_match_set *set;
    const char *q = p + 1, *r;
    size_t cost;
    int i, c, sig = 1;

    for (i = 0; i < WSG_MATCH_SETS; i++)
        if (m->sets[i].p == p)
            return i;
    /* Where it ends, as Lua's classend finds it: an escape takes the
     * byte after it, even a ']'. The NUL after the pattern stops it. */
    if (*q == '^')
        q++;
    do {
        if (q == m->p_end)
            return error_at(m, "malformed pattern (missing ']')"), -1;
        if (*q++ == ESC && q < m->p_end)
            q++;
    } while (*q != ']');
    i = m->next;
    m->next = (m->next + 1) % WSG_MATCH_SETS;
    set = &m->sets[i];
    set->p = p;
    set->ep = q + 1;
    memset(set->bits, 0, sizeof set->bits);
    cost = (size_t)(q - p);
    /* Its members, read as Lua's matchbracketclass reads them. */
    r = p;
    if (r[1] == '^') {
        sig = 0;
        r++;
    }
    while (++r < q) {
        if (*r == ESC) {
            r++;
            for (c = 0; c < 256; c++)
                if (class_match(c, (unsigned char)*r))
                    bits_set(set->bits, c);
            cost += 256;
        } else if (r[1] == '-' && r + 2 < q) {
            r += 2;
            for (c = (unsigned char)r[-2]; c <= (unsigned char)*r; c++)
                bits_set(set->bits, c);
        } else {
            bits_set(set->bits, (unsigned char)*r);
        }
    }
    if (!sig)
        for (c = 0; c < 32; c++)
            set->bits[c] = (unsigned char)~set->bits[c];
    *steps = cost < *steps ? *steps - (uint32_t)cost : 0;
    return i;
}

/* Where the single item at p ends (at its quantifier, if any); *set the
 * index of its set, -1 for none. NULL with the error set. */
static const char *item_end(struct wsg_match *m, const char *p, int *set,
                            uint32_t *steps)
{
    *set = -1;
    if (*p == ESC) {
        if (p + 1 == m->p_end) {
            error_at(m, "malformed pattern (ends with '%')");
            return NULL;
        }
        return p + 2;
    }
    if (*p == '[') {
        *set = set_get(m, p, steps);
        return *set < 0 ? NULL : m->sets[*set].ep;
    }
    return p + 1;
}

/* Does the subject byte at s match the single item at p? */
static int item_match(const struct wsg_match *m, const char *s, const char *p,
                      int set)
{
    int c;

    if (s >= m->src_end)
        return 0;
    c = (unsigned char)*s;
    switch (*p) {
    case '.':
        return 1;
    case ESC:
        return class_match(c, (unsigned char)p[1]);
    case '[':
        return bits_has(m->sets[set].bits, c);
    default:
        return (unsigned char)*p == c;
    }
}

static struct wsg_match_choice *push(struct wsg_match *m, int kind)
{
    struct wsg_match_choice *ch;

    /* The match itself is one of Lua's 200 levels. */
    if (m->top >= WSG_MATCH_DEPTH - 1) {
        error_at(m, "pattern too complex");
        return NULL;
    }
    ch = &m->stack[m->top++];
    ch->kind = (unsigned char)kind;
    return ch;
}

void wsg_match_init(struct wsg_match *m, const char *s, size_t ls,
                    const char *p, size_t lp)
{
    int i;

    m->src = s;
    m->src_end = s + ls;
    m->pat = p;
    m->p_end = p + lp;
    m->error[0] = '\0';
    m->end = NULL;
    m->next = 0;
    for (i = 0; i < WSG_MATCH_SETS; i++)
        m->sets[i].p = NULL;
    wsg_match_at(m, s);
}

void wsg_match_at(struct wsg_match *m, const char *s)
{
    m->level = 0;
    m->top = 0;
    m->mode = M_ITEM;
    m->s = s;
    m->p = m->pat;
}

/* '%' and a digit: a back-reference to a capture. */
static int item_backref(struct wsg_match *m)
{
    int l = m->p[1] - '1';

    if (l < 0 || l >= m->level || m->cap[l].len == WSG_MATCH_UNFINISHED) {
        snprintf(m->error, sizeof m->error, "invalid capture index %%%d",
                 l + 1);
        return WSG_MATCH_ERROR;
    }
    /* A position capture has no bytes to compare: Lua fails it. */
    if (m->cap[l].len == WSG_MATCH_POSITION ||
        (size_t)(m->src_end - m->s) < (size_t)m->cap[l].len)
        return WSG_MATCH_NO;
    m->ref = l;
    m->count = 0;
    m->mode = M_BACKREF;
    return GO;
}

/* '%b' and '%f', the escapes that are not classes; the rest go on as
 * single items (-2). */
static int item_escape(struct wsg_match *m, uint32_t *steps)
{
    const char *p = m->p, *ep;
    int set, prev, cur;

    switch (p[1]) {
    case 'b':
        if (p + 2 >= m->p_end - 1)
            return error_at(m, "malformed pattern (missing arguments to "
                               "'%b')");
        if (m->s >= m->src_end || *m->s != p[2])
            return WSG_MATCH_NO;
        m->scan = m->s + 1;
        m->count = 1;
        m->mode = M_BALANCE;
        return GO;
    case 'f':
        p += 2;
        if (*p != '[')
            return error_at(m, "missing '[' after '%f' in pattern");
        ep = item_end(m, p, &set, steps);
        if (!ep)
            return WSG_MATCH_ERROR;
        prev = m->s == m->src ? 0 : (unsigned char)m->s[-1];
        cur = m->s < m->src_end ? (unsigned char)*m->s : 0;
        if (bits_has(m->sets[set].bits, prev) ||
            !bits_has(m->sets[set].bits, cur))
            return WSG_MATCH_NO;
        m->p = ep;
        return GO;
    default:
        if (isdigit((unsigned char)p[1]))
            return item_backref(m);
        return -2;
    }
}

/* One pattern item at m->s, m->p. */
static int item(struct wsg_match *m, uint32_t *steps)
{
    struct wsg_match_choice *ch;
    const char *s = m->s, *p = m->p, *ep;
    int set, l, r;

    if (p == m->p_end) {
        m->end = s;
        return WSG_MATCH_YES;
    }
    switch (*p) {
    case '(':
        if (m->level >= WSG_MATCH_CAPTURES)
            return error_at(m, "too many captures");
        if (!push(m, C_OPEN))
            return WSG_MATCH_ERROR;
        m->cap[m->level].init = s;
        m->cap[m->level].len =
            p[1] == ')' ? WSG_MATCH_POSITION : WSG_MATCH_UNFINISHED;
        m->level++;
        m->p = p + (p[1] == ')' ? 2 : 1);
        return GO;
    case ')':
        for (l = m->level - 1; l >= 0; l--)
            if (m->cap[l].len == WSG_MATCH_UNFINISHED)
                break;
        if (l < 0)
            return error_at(m, "invalid pattern capture");
        if (!(ch = push(m, C_CLOSE)))
            return WSG_MATCH_ERROR;
        ch->cap = l;
        m->cap[l].len = s - m->cap[l].init;
        m->p = p + 1;
        return GO;
    case '$':
        if (p + 1 != m->p_end)
            break;
        if (s != m->src_end)
            return WSG_MATCH_NO;
        m->end = s;
        return WSG_MATCH_YES;
    case ESC:
        r = item_escape(m, steps);
        if (r != -2)
            return r;
        break;
    default:
        break;
    }
    /* A single item and its quantifier. */
    ep = item_end(m, p, &set, steps);
    if (!ep)
        return WSG_MATCH_ERROR;
    if (!item_match(m, s, p, set)) {
        if (*ep == '*' || *ep == '?' || *ep == '-') {
            m->p = ep + 1;
            return GO;
        }
        return WSG_MATCH_NO;
    }
    switch (*ep) {
    case '?':
        if (!(ch = push(m, C_OPT)))
            return WSG_MATCH_ERROR;
        ch->s = s;
        ch->p = ep + 1;
        m->s = s + 1;
        m->p = ep + 1;
        return GO;
    case '+':
        s++;
        /* fall through */
    case '*':
        m->ep = ep;
        m->set = set;
        m->scan = s;
        m->count = 0;
        m->mode = M_EXPAND;
        return GO;
    case '-':
        if (!(ch = push(m, C_MIN)))
            return WSG_MATCH_ERROR;
        ch->s = s;
        ch->p = p;
        ch->ep = ep;
        m->p = ep + 1;
        return GO;
    default:
        m->s = s + 1;
        m->p = ep;
        return GO;
    }
}

/* What follows the newest choice failed: undo or try its next way. */
static int fail(struct wsg_match *m, uint32_t *steps)
{
    struct wsg_match_choice *ch;
    int set;

    if (m->top == 0)
        return WSG_MATCH_NO;
    ch = &m->stack[m->top - 1];
    switch (ch->kind) {
    case C_OPEN:
        m->level--;
        break;
    case C_CLOSE:
        m->cap[ch->cap].len = WSG_MATCH_UNFINISHED;
        break;
    case C_OPT:
        m->s = ch->s;
        m->p = ch->p;
        m->top--;
        m->mode = M_ITEM;
        return GO;
    case C_MAX:
        if (ch->n == 0)
            break;
        ch->n--;
        m->s = ch->s + ch->n;
        m->p = ch->ep + 1;
        m->mode = M_ITEM;
        return GO;
    case C_MIN:
        /* The item was read before: no error can come now. */
        if (!item_end(m, ch->p, &set, steps))
            return WSG_MATCH_ERROR;
        if (!item_match(m, ch->s, ch->p, set))
            break;
        ch->s++;
        m->s = ch->s;
        m->p = ch->ep + 1;
        m->mode = M_ITEM;
        return GO;
    }
    m->top--;
    return GO;
}

/* The scans: a byte (or a piece of a back-reference) for the step the
 * machine took, then one a step while steps last. The first is free of
 * the steps left, or a slice of one step would never get past it. */
static int scan_expand(struct wsg_match *m, uint32_t *steps)
{
    struct wsg_match_choice *ch;

    while (item_match(m, m->scan + m->count, m->p, m->set)) {
        m->count++;
        if (*steps == 0)
            return WSG_MATCH_MORE;
        (*steps)--;
    }
    /* The longest first; each failure gives one back. */
    if (!(ch = push(m, C_MAX)))
        return WSG_MATCH_ERROR;
    ch->s = m->scan;
    ch->n = m->count;
    ch->p = m->p;
    ch->ep = m->ep;
    m->s = m->scan + m->count;
    m->p = m->ep + 1;
    m->mode = M_ITEM;
    return GO;
}

static int scan_balance(struct wsg_match *m, uint32_t *steps)
{
    char open = m->p[2], close = m->p[3];

    while (m->scan < m->src_end) {
        /* The closing byte first, as Lua: %b"" closes at the next '"'. */
        if (*m->scan == close) {
            if (--m->count == 0) {
                m->s = m->scan + 1;
                m->p += 4;
                m->mode = M_ITEM;
                return GO;
            }
        } else if (*m->scan == open) {
            m->count++;
        }
        m->scan++;
        if (*steps == 0)
            return WSG_MATCH_MORE;
        (*steps)--;
    }
    m->mode = M_FAIL;
    return GO;
}

static int scan_backref(struct wsg_match *m, uint32_t *steps)
{
    size_t len = (size_t)m->cap[m->ref].len, n;

    while (m->count < len) {
        n = len - m->count;
        if (n > WSG_MATCH_BYTES_PER_STEP)
            n = WSG_MATCH_BYTES_PER_STEP;
        if (memcmp(m->cap[m->ref].init + m->count, m->s + m->count, n) != 0) {
            m->mode = M_FAIL;
            return GO;
        }
        m->count += n;
        if (m->count < len) {
            if (*steps == 0)
                return WSG_MATCH_MORE;
            (*steps)--;
        }
    }
    m->s += len;
    m->p += 2;
    m->mode = M_ITEM;
    return GO;
}

enum wsg_match_result wsg_match_run(struct wsg_match *m, uint32_t *steps)
{
    int r;

    for (;;) {
        if (*steps == 0)
            return WSG_MATCH_MORE;
        (*steps)--;
        switch (m->mode) {
        case M_ITEM:
            r = item(m, steps);
            if (r == WSG_MATCH_NO) {
                m->mode = M_FAIL;
                r = GO;
            }
            break;
        case M_FAIL:
            r = fail(m, steps);
            break;
        case M_EXPAND:
            r = scan_expand(m, steps);
            break;
        case M_BALANCE:
            r = scan_balance(m, steps);
            break;
        default:
            r = scan_backref(m, steps);
            break;
        }
        if (r != GO)
            return (enum wsg_match_result)r;
    }
}
