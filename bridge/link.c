/*
 * link.c — device backends of ampath-bridge (libserialport for serial ports, a raw fd for ptys: docs/bridge.md).
 *
 * libserialport (0.1.1) cannot open pseudo-terminals (names must start with
 * /dev/, symlinks are not resolved, sp_open fails on TIOCMGET), so: resolve the
 * path with realpath() (users type /dev/serial/by-id/... links), use
 * libserialport for real serial devices, and a raw termios descriptor for ptys
 * (Klipper's /tmp/printer, the virtual printer). Both end as one fd for poll();
 * writes go through write(2) on that fd, because sp_nonblocking_write reports
 * EAGAIN as SP_ERR_FAIL in 0.1.1.
 */
#define _DEFAULT_SOURCE
#define _XOPEN_SOURCE 600

#include <errno.h>
#include <fcntl.h>
#include <libserialport.h>
#include <stdlib.h>
#include <string.h>
#include <sys/file.h>
#include <sys/ioctl.h>
#include <sys/stat.h>
#include <sys/sysmacros.h>
#include <termios.h>
#include <unistd.h>

#include "bridge.h"

static int is_pty_path(const char *real)
{
    struct stat st;
    if (strncmp(real, "/dev/pts/", 9) == 0)
        return 1;
    if (stat(real, &st) == 0 && S_ISCHR(st.st_mode) && major(st.st_rdev) >= 136 && major(st.st_rdev) <= 143)
        return 1; /* Unix98 pty slaves */
    return 0;
}

static speed_t std_speed(long baud)
{
    switch (baud) {
    case 9600: return B9600;
    case 19200: return B19200;
    case 38400: return B38400;
    case 57600: return B57600;
    case 115200: return B115200;
    case 230400: return B230400;
    default: return 0;
    }
}

static int open_raw(br_link *l, long baud, char *why, size_t whylen)
{
    struct termios t;
    speed_t sp;
    l->fd = open(l->real, O_RDWR | O_NOCTTY | O_NONBLOCK);
    if (l->fd < 0) {
        snprintf(why, whylen, "cannot open %s: %s", l->real, strerror(errno));
        return -1;
    }
    if (tcgetattr(l->fd, &t) == 0) {
        cfmakeraw(&t);
        t.c_cflag |= CLOCAL | CREAD;
        t.c_cc[VMIN] = 0;
        t.c_cc[VTIME] = 0;
        sp = std_speed(baud);
        if (sp) {
            cfsetispeed(&t, sp);
            cfsetospeed(&t, sp);
        }
        /* TCSANOW, not TCSAFLUSH: a boot banner already waiting must not be thrown away */
        tcsetattr(l->fd, TCSANOW, &t);
    }
    return 0;
}

static int open_sp(br_link *l, long baud, char *why, size_t whylen)
{
    struct sp_port *port = NULL;
    int fd = -1;
    if (sp_get_port_by_name(l->real, &port) != SP_OK) {
        snprintf(why, whylen, "%s is not a serial port libserialport knows", l->real);
        return -1;
    }
    if (sp_open(port, SP_MODE_READ_WRITE) != SP_OK) {
        char *msg = sp_last_error_message();
        snprintf(why, whylen, "cannot open %s: %s", l->real, msg ? msg : "error");
        if (msg)
            sp_free_error_message(msg);
        sp_free_port(port);
        return -1;
    }
    /* libserialport sets non-standard rates such as 250000 through termios2 */
    if (sp_set_baudrate(port, (int)baud) != SP_OK || sp_set_bits(port, 8) != SP_OK ||
        sp_set_parity(port, SP_PARITY_NONE) != SP_OK || sp_set_stopbits(port, 1) != SP_OK ||
        sp_set_flowcontrol(port, SP_FLOWCONTROL_NONE) != SP_OK || sp_get_port_handle(port, &fd) != SP_OK) {
        snprintf(why, whylen, "cannot configure %s at %ld baud", l->real, baud);
        sp_close(port);
        sp_free_port(port);
        return -1;
    }
    fcntl(fd, F_SETFL, fcntl(fd, F_GETFL) | O_NONBLOCK);
    l->sp = port;
    l->fd = fd;
    return 0;
}

static int link_open(br_link *l, const char *path, long baud, char *why, size_t whylen)
{
    memset(l, 0, sizeof *l);
    l->fd = -1;
    if (!realpath(path, l->real)) {
        snprintf(why, whylen, "%s: %s", path, strerror(errno));
        return -1;
    }
    l->is_pty = is_pty_path(l->real);
    if (l->is_pty)
        return open_raw(l, baud, why, whylen);
    if (open_sp(l, baud, why, whylen) == 0)
        return 0;
    /* other terminals libserialport does not list (e.g. tty0tty, socat links): raw termios */
    {
        char why2[256];
        if (open_raw(l, baud, why2, sizeof why2) == 0 && isatty(l->fd))
            return 0;
    }
    if (l->fd >= 0)
        close(l->fd);
    l->fd = -1;
    return -1;
}

/* Hardening: two programs must never share a printer. flock() is what pyserial's exclusive=True (OctoPrint)
   and other hosts take; TIOCEXCL refuses any further open() (root excepted). TIOCEXCL only on real serial
   ports: their flag ends with the last close, while a pty whose other end keeps the slave open (Klipper,
   the virtual printer) would stay exclusive after a crashed bridge and lock out its successor. */
static int link_lock(br_link *l, char *why, size_t whylen)
{
    if (flock(l->fd, LOCK_EX | LOCK_NB) != 0) {
        snprintf(why, whylen, "%s is in use by another program (it holds a lock on the device): %s", l->real,
                 errno == EWOULDBLOCK ? "another ampath-bridge, or a host such as OctoPrint" : strerror(errno));
        return -1;
    }
    if (!l->is_pty)
        ioctl(l->fd, TIOCEXCL);
    return 0;
}

int br_link_open(br_link *l, const char *path, long baud, char *why, size_t whylen)
{
    if (link_open(l, path, baud, why, whylen) != 0)
        return -1;
    if (link_lock(l, why, whylen) != 0) {
        br_link_close(l);
        return -1;
    }
    return 0;
}

void br_link_close(br_link *l)
{
    if (l->fd >= 0 && !l->is_pty)
        ioctl(l->fd, TIOCNXCL);
    if (l->sp) {
        sp_close((struct sp_port *)l->sp);
        sp_free_port((struct sp_port *)l->sp);
        l->sp = NULL;
    } else if (l->fd >= 0) {
        close(l->fd);
    }
    l->fd = -1;
}
