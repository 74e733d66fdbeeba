/*
 * Which names the web page answers to, and which pages may change
 * something through it (DNS rebinding and cross-site requests). A site
 * that points its own name at the gripper's address gets its pages into
 * the same origin as the gripper's page, so a browser lets them read and
 * drive it: the Host header must name the gripper, not merely reach it.
 * The names are the loopback ones (an IPv4 literal of 127/8, localhost,
 * [::1]), the address the page listens on when it is one address, and
 * what --web-host lists; nothing else, whatever the address it listens
 * on. A Host header is read exactly (no prefix of a name, no trailing
 * label, no number in another base): a name, an optional :PORT of digits
 * in 1..65535, nothing else. Pure functions, apart from the server, so
 * that the options check --web-host's names by the same rules and the
 * tests call them directly.
 */
#ifndef WSG_DAEMON_WEB_HOST_H
#define WSG_DAEMON_WEB_HOST_H

#include <stddef.h>
#include <stdint.h>

/* The longest name --web-host takes (a DNS name's 253 characters, or an
 * IPv6 literal in brackets). */
#define WSG_WEB_HOST_NAME_MAX 253u

/* value (len bytes) as HOST[:PORT]: HOST's bytes into *host and *host_len
 * (an IPv6 literal with its brackets), PORT into *port (0: none). 0, or
 * -EINVAL when it is not that: empty, a port that is not 1..65535 in
 * digits, anything after it. HOST's characters are checked by who
 * compares it. */
int wsg_web_host_split(const char *value, size_t len, const char **host,
                       size_t *host_len, unsigned *port);

/* An IPv4 literal (four decimal numbers 0..255 without leading zeros,
 * dot-separated, nothing else) into addr. 0 or -EINVAL. */
int wsg_web_host_ipv4(const char *s, size_t n, uint8_t addr[4]);

/* 1 when host (n bytes, no port) is a loopback name: an IPv4 literal of
 * 127/8, localhost, [::1] (any case); else 0. */
int wsg_web_host_loopback(const char *host, size_t n);

/* A name --web-host may list (n bytes): a DNS name (labels of letters,
 * digits and inner hyphens, 1..63 characters each, dot-separated, 253 at
 * most, no trailing dot), an IPv4 literal, or an IPv6 literal in
 * brackets (hex digits, ':' and '.'). No port, no wildcard. 0 or
 * -EINVAL. */
int wsg_web_host_name_valid(const char *name, size_t n);

/* Whether the page answers a request with the Host header value (NULL:
 * none; that is refused too): HOST[:PORT] whose HOST is a loopback name,
 * the IPv4 address bound (the one the page listens on; 0.0.0.0 names
 * none), or one of allow's names (comma-separated, compared without
 * regard to case; NULL or "": none). 1 or 0. */
int wsg_web_host_allowed(const char *value, const char *allow,
                         const uint8_t bound[4]);

/* Whether a request that changes something may come from origin (the
 * Origin header; NULL: none, a client that is no browser: 1): only
 * "http://HOST[:PORT]" naming the page itself, i.e. whose HOST the page
 * answers to (as wsg_web_host_allowed) and whose HOST and PORT are the
 * request's Host header's (a port left out being 80). 1 or 0. */
int wsg_web_origin_allowed(const char *origin, const char *host,
                           const char *allow, const uint8_t bound[4]);

#endif
