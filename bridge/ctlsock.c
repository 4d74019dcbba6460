/*
 * ctlsock.c — where the control socket lives and how it is taken:
 * whoever can connect can drive the printer, so the socket sits in a directory
 * only its user can enter, is created 0600, and replaces nothing but a stale
 * socket of the same user (no daemon answers on it). A live daemon, a regular
 * file or another user's socket at the path are refused and left alone.
 */
#define _DEFAULT_SOURCE
#define _POSIX_C_SOURCE 200809L

#include <errno.h>
#include <fcntl.h>
#include <stdlib.h>
#include <string.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <sys/un.h>
#include <unistd.h>

#include "daemon.h"

/* A directory that is ours and closed to everyone else (a symlink does not count). */
static int private_dir(const char *dir, char *why, size_t whylen)
{
    struct stat st;
    if (lstat(dir, &st) != 0) {
        snprintf(why, whylen, "%s: %s", dir, strerror(errno));
        return -1;
    }
    if (!S_ISDIR(st.st_mode)) {
        snprintf(why, whylen, "%s is not a directory (a symlink or file there is not ours to trust): use --socket",
                 dir);
        return -1;
    }
    if (st.st_uid != getuid() || (st.st_mode & 077) != 0) {
        snprintf(why, whylen,
                 "%s is not private (owner uid %ld, mode %03o; it must be ours with mode 0700): another user could "
                 "receive the commands; remove it or use --socket",
                 dir, (long)st.st_uid, (unsigned)(st.st_mode & 0777));
        return -1;
    }
    return 0;
}

int br_sock_default(char *out, size_t cap, char *why, size_t whylen)
{
    const char *rt = getenv("XDG_RUNTIME_DIR"), *tmp = getenv("TMPDIR");
    char dir[PATH_MAX];
    if (rt && *rt) {
        if (private_dir(rt, why, whylen) != 0)
            return -1;
        if ((size_t)snprintf(out, cap, "%s/ampath-bridge.sock", rt) >= cap)
            goto toolong;
        return 0;
    }
    if (!tmp || !*tmp)
        tmp = "/tmp";
    if ((size_t)snprintf(dir, sizeof dir, "%s/ampath-bridge-%ld", tmp, (long)getuid()) >= sizeof dir)
        goto toolong;
    if (mkdir(dir, 0700) != 0 && errno != EEXIST) {
        snprintf(why, whylen, "cannot create %s: %s", dir, strerror(errno));
        return -1;
    }
    if (private_dir(dir, why, whylen) != 0)
        return -1;
    if ((size_t)snprintf(out, cap, "%s/ctl.sock", dir) >= cap)
        goto toolong;
    return 0;
toolong:
    snprintf(why, whylen, "socket path too long");
    return -1;
}

/* The path is taken by something: refuse unless it is our own socket and nobody answers on it. */
static int stale(const char *path, const struct sockaddr_un *sa, char *why, size_t whylen)
{
    struct stat st;
    int c, r, e;
    if (lstat(path, &st) != 0)
        return errno == ENOENT ? 0 : (snprintf(why, whylen, "%s: %s", path, strerror(errno)), -1);
    if (!S_ISSOCK(st.st_mode)) {
        snprintf(why, whylen, "%s exists and is not a socket: left alone (choose another --socket)", path);
        return -1;
    }
    if (st.st_uid != getuid()) {
        snprintf(why, whylen, "%s is a socket of uid %ld: left alone", path, (long)st.st_uid);
        return -1;
    }
    c = socket(AF_UNIX, SOCK_STREAM, 0);
    if (c < 0) {
        snprintf(why, whylen, "socket: %s", strerror(errno));
        return -1;
    }
    r = connect(c, (const struct sockaddr *)sa, sizeof *sa);
    e = errno;
    close(c);
    if (r == 0 || e == EAGAIN) {
        snprintf(why, whylen, "a daemon is already listening on %s (send it 'quit' first)", path);
        return -1;
    }
    if (e != ECONNREFUSED) {
        snprintf(why, whylen, "cannot tell whether a daemon listens on %s (%s): left alone", path, strerror(e));
        return -1;
    }
    if (unlink(path) != 0 && errno != ENOENT) {
        snprintf(why, whylen, "cannot remove the stale socket %s: %s", path, strerror(errno));
        return -1;
    }
    return 0;
}

int br_sock_listen(br_listener *l, const char *path, char *why, size_t whylen)
{
    struct sockaddr_un sa;
    struct stat st;
    int attempt;
    memset(l, 0, sizeof *l);
    l->fd = -1;
    memset(&sa, 0, sizeof sa);
    sa.sun_family = AF_UNIX;
    if (strlen(path) >= sizeof sa.sun_path) {
        snprintf(why, whylen, "socket path too long (%lu bytes at most): %s", (unsigned long)sizeof sa.sun_path - 1,
                 path);
        return -1;
    }
    strcpy(sa.sun_path, path);
    snprintf(l->path, sizeof l->path, "%s", path);
    l->fd = socket(AF_UNIX, SOCK_STREAM, 0);
    if (l->fd < 0) {
        snprintf(why, whylen, "socket: %s", strerror(errno));
        return -1;
    }
    for (attempt = 0;; attempt++) {
        mode_t old = umask(077); /* 0600 from the start: no window where others could connect */
        int r = bind(l->fd, (struct sockaddr *)&sa, sizeof sa), e = errno;
        umask(old);
        if (r == 0)
            break;
        if (e != EADDRINUSE || attempt > 0) {
            snprintf(why, whylen, "cannot bind %s: %s", path, strerror(e));
            goto fail;
        }
        if (stale(path, &sa, why, whylen) != 0)
            goto fail;
    }
    if (listen(l->fd, 16) != 0 || lstat(path, &st) != 0) {
        snprintf(why, whylen, "cannot listen on %s: %s", path, strerror(errno));
        goto fail;
    }
    chmod(path, 0600);
    l->dev = st.st_dev;
    l->ino = st.st_ino;
    fcntl(l->fd, F_SETFL, fcntl(l->fd, F_GETFL) | O_NONBLOCK);
    fcntl(l->fd, F_SETFD, FD_CLOEXEC);
    return 0;
fail:
    close(l->fd);
    l->fd = -1;
    return -1;
}

void br_sock_close(br_listener *l)
{
    struct stat st;
    if (l->fd < 0)
        return;
    close(l->fd);
    l->fd = -1;
    /* a successor may have taken the path already: remove only what we created */
    if (lstat(l->path, &st) == 0 && S_ISSOCK(st.st_mode) && st.st_dev == l->dev && st.st_ino == l->ino)
        unlink(l->path);
}
