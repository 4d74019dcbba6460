/*
 * clients.c — control-socket connections that no client can wedge:
 * sockets are non-blocking, input and output are bounded (a line longer than
 * BR_CL_IN is discarded whole up to its newline; a client whose replies pile
 * up past BR_CL_OUT is disconnected rather than waited for), idle clients are
 * closed, and when every ordinary slot is taken a connection still gets one
 * of BR_CL_RESERVED slots for one priority command (estop, cancel, status,
 * pause) — the oldest reserved connection is evicted if need be, so an
 * emergency stop always gets through.
 */
#define _DEFAULT_SOURCE
#define _POSIX_C_SOURCE 200809L

#include <errno.h>
#include <fcntl.h>
#include <stdio.h>
#include <string.h>
#include <sys/socket.h>
#include <unistd.h>

#include "daemon.h"

void br_clients_init(br_clients *cs, int lfd, double idle_s)
{
    int i;
    memset(cs, 0, sizeof *cs);
    cs->lfd = lfd;
    cs->idle_s = idle_s;
    for (i = 0; i < BR_CL_MAX; i++)
        cs->cl[i].fd = -1;
}

void br_client_drop(br_clients *cs, br_client *c)
{
    (void)cs;
    if (c->fd >= 0)
        close(c->fd);
    c->fd = -1;
    c->inlen = c->outlen = c->outoff = 0;
    c->subscribed = c->discarding = c->closing = c->eof = c->reserved = 0;
}

static void flush(br_clients *cs, br_client *c, double now)
{
    while (c->fd >= 0 && c->outoff < c->outlen) {
        ssize_t w = send(c->fd, c->out + c->outoff, c->outlen - c->outoff, MSG_NOSIGNAL | MSG_DONTWAIT);
        if (w > 0) {
            c->outoff += (size_t)w;
            c->t_active = now;
        } else {
            if (w < 0 && errno != EAGAIN && errno != EWOULDBLOCK && errno != EINTR)
                br_client_drop(cs, c);
            return;
        }
    }
    if (c->fd >= 0 && c->outoff == c->outlen)
        c->outoff = c->outlen = 0;
}

int br_client_send(br_clients *cs, br_client *c, const char *text, size_t n)
{
    if (c->fd < 0)
        return -1;
    if (c->outoff > 0 && c->outlen + n > BR_CL_OUT) {
        memmove(c->out, c->out + c->outoff, c->outlen - c->outoff);
        c->outlen -= c->outoff;
        c->outoff = 0;
    }
    if (c->outlen + n > BR_CL_OUT) {
        /* it does not read: waiting for it would stall the printer and everyone else */
        cs->dropped++;
        br_client_drop(cs, c);
        return -1;
    }
    memcpy(c->out + c->outlen, text, n);
    c->outlen += n;
    flush(cs, c, c->t_active);
    return 0;
}

static void say(br_clients *cs, br_client *c, int json, const char *msg)
{
    char buf[256];
    int n = json ? snprintf(buf, sizeof buf, "{\"ok\":false,\"error\":\"%s\"}\n", msg)
                 : snprintf(buf, sizeof buf, "error %s\n", msg);
    br_client_send(cs, c, buf, (size_t)n);
}

static br_client *slot_for_new(br_clients *cs, double now)
{
    int i, oldest = -1;
    for (i = 0; i < BR_CL_NORMAL; i++)
        if (cs->cl[i].fd < 0)
            return &cs->cl[i];
    for (i = BR_CL_NORMAL; i < BR_CL_MAX; i++) {
        if (cs->cl[i].fd < 0)
            return &cs->cl[i];
        if (oldest < 0 || cs->cl[i].t_open < cs->cl[oldest].t_open)
            oldest = i;
    }
    br_client_drop(cs, &cs->cl[oldest]); /* reserved slots are short-lived: the newest may be the estop */
    (void)now;
    return &cs->cl[oldest];
}

static void accept_all(br_clients *cs, double now)
{
    for (;;) {
        br_client *c;
        int fd = accept(cs->lfd, NULL, NULL);
        if (fd < 0)
            return; /* EAGAIN: all taken; other errors (EMFILE) retried on the next turn */
        fcntl(fd, F_SETFL, fcntl(fd, F_GETFL) | O_NONBLOCK);
        fcntl(fd, F_SETFD, FD_CLOEXEC);
        c = slot_for_new(cs, now);
        br_client_drop(cs, c);
        c->fd = fd;
        c->reserved = c >= &cs->cl[BR_CL_NORMAL];
        c->t_active = c->t_open = now;
    }
}

/* Hand every complete line to fn; an over-long line is discarded whole and answered once. */
static void lines(br_clients *cs, br_client *c, br_line_fn fn, void *user)
{
    size_t start = 0;
    while (c->fd >= 0 && !c->closing) {
        char *nl = memchr(c->in + start, '\n', c->inlen - start);
        size_t len;
        if (!nl && c->eof && start < c->inlen)
            nl = c->in + c->inlen; /* the last line of a client that closed its side */
        if (!nl)
            break;
        len = (size_t)(nl - (c->in + start));
        if (c->discarding) {
            char msg[80];
            snprintf(msg, sizeof msg, "line too long (%d bytes at most): discarded", BR_CL_IN - 1);
            say(cs, c, c->discarding == 2, msg);
            c->discarding = 0;
        } else {
            if (len > 0 && c->in[start + len - 1] == '\r')
                len--;
            fn(user, c, c->in + start, len);
            if (c->fd >= 0 && c->reserved && len > 0)
                c->closing = 1; /* one command per reserved connection */
        }
        start = (size_t)(nl - c->in) + 1;
        if (start > c->inlen)
            start = c->inlen;
    }
    if (c->fd < 0)
        return;
    memmove(c->in, c->in + start, c->inlen - start);
    c->inlen -= start;
    if (c->inlen == BR_CL_IN) {
        size_t i = 0;
        while (i < c->inlen && (c->in[i] == ' ' || c->in[i] == '\t'))
            i++;
        c->discarding = i < c->inlen && c->in[i] == '{' ? 2 : 1;
        c->inlen = 0;
    }
    if (c->eof)
        c->closing = 1;
}

static void input(br_clients *cs, br_client *c, short re, double now, br_line_fn fn, void *user)
{
    ssize_t r;
    if (c->closing) {
        if (re & (POLLHUP | POLLERR))
            br_client_drop(cs, c);
        return;
    }
    if (!(re & (POLLIN | POLLHUP | POLLERR)))
        return;
    r = recv(c->fd, c->in + c->inlen, BR_CL_IN - c->inlen, MSG_DONTWAIT);
    if (r < 0) {
        if (errno != EAGAIN && errno != EWOULDBLOCK && errno != EINTR)
            br_client_drop(cs, c);
        return;
    }
    if (r == 0)
        c->eof = 1; /* `echo status | socat - UNIX-CONNECT:...` closes its side and waits for the reply */
    c->inlen += (size_t)r;
    c->t_active = now;
    if (c->discarding) {
        char *nl = memchr(c->in, '\n', c->inlen);
        if (!nl) {
            c->inlen = 0;
            if (c->eof)
                c->closing = 1;
            return;
        }
        /* keep the newline: lines() answers the discarded line when it reaches it */
        memmove(c->in, nl, c->inlen - (size_t)(nl - c->in));
        c->inlen -= (size_t)(nl - c->in);
    }
    lines(cs, c, fn, user);
}

static void timeouts(br_clients *cs, br_client *c, double now)
{
    if (c->fd < 0)
        return;
    if (c->closing) {
        if (c->outlen == 0 || now - c->t_active > BR_CLOSING_S)
            br_client_drop(cs, c);
    } else if (c->reserved && now - c->t_open > BR_RESERVED_S) {
        br_client_drop(cs, c);
    } else if (!c->subscribed && cs->idle_s > 0 && now - c->t_active > cs->idle_s) {
        say(cs, c, 0, "idle timeout: closed");
        if (c->fd >= 0)
            c->closing = 1;
    }
}

int br_clients_pollfds(br_clients *cs, struct pollfd *pfd, int cap)
{
    int i, n = 0;
    if (cap < 1)
        return 0;
    pfd[n].fd = cs->lfd;
    pfd[n].events = POLLIN;
    pfd[n].revents = 0;
    n++;
    for (i = 0; i < BR_CL_MAX && n < cap; i++) {
        br_client *c = &cs->cl[i];
        if (c->fd < 0)
            continue;
        pfd[n].fd = c->fd;
        pfd[n].events = (short)((c->closing ? 0 : POLLIN) | (c->outlen > c->outoff ? POLLOUT : 0));
        pfd[n].revents = 0;
        n++;
    }
    return n;
}

void br_clients_service(br_clients *cs, const struct pollfd *pfd, int n, double now, br_line_fn fn, void *user)
{
    int i, k;
    for (k = 1; k < n; k++) {
        for (i = 0; i < BR_CL_MAX; i++) {
            br_client *c = &cs->cl[i];
            if (c->fd < 0 || c->fd != pfd[k].fd)
                continue;
            input(cs, c, pfd[k].revents, now, fn, user);
            if (c->fd >= 0)
                flush(cs, c, now);
            break;
        }
    }
    for (i = 0; i < BR_CL_MAX; i++)
        timeouts(cs, &cs->cl[i], now);
    if (n > 0 && (pfd[0].revents & POLLIN))
        accept_all(cs, now); /* after the closed ones left: their slots are free again */
}

int br_clients_wait_ms(const br_clients *cs, double now, int cap)
{
    int i;
    double t = (double)cap / 1000.0;
    for (i = 0; i < BR_CL_MAX; i++) {
        const br_client *c = &cs->cl[i];
        double d = t;
        if (c->fd < 0)
            continue;
        if (c->closing)
            d = BR_CLOSING_S - (now - c->t_active);
        else if (c->reserved)
            d = BR_RESERVED_S - (now - c->t_open);
        else if (!c->subscribed && cs->idle_s > 0)
            d = cs->idle_s - (now - c->t_active);
        if (d < t)
            t = d;
    }
    return t <= 0 ? 0 : (int)(t * 1000.0) + 1;
}

void br_clients_close_all(br_clients *cs)
{
    int i;
    for (i = 0; i < BR_CL_MAX; i++)
        br_client_drop(cs, &cs->cl[i]);
}
