/* SPDX-License-Identifier: Apache-2.0 */
/* Linux port: CAN on a SocketCAN raw socket (PF_CAN, SOCK_RAW, CAN_RAW),
 * non-blocking, classic 11-bit data frames only.
 *
 * Received frames pass through a fixed ring (PMA_HAL_LINUX_CAN_RX_DEPTH) that
 * is filled from the socket whenever the port reads it: by pma_hal_can_recv()
 * when the ring is empty, by send/status/recover (so that error frames are
 * seen), and by the lockstep tick wait, which has to look at frames to find
 * the tick without taking them from the application. The port never reads
 * more than the ring holds, so it never drops a frame itself: what cannot be
 * queued stays in the socket, and frames lost there (socket buffer full,
 * SO_RXQ_OVFL) or in the controller (CAN_ERR_CRTL_RX_OVERFLOW) are the
 * rx_overruns.
 *
 * Error frames (CAN_RAW_ERR_FILTER: controller problems, bus-off, restarted)
 * update the fault confinement state (linux_can_err.c). Bus-off is latched
 * until pma_hal_can_recover(): see its comment for what that does on Linux. */
#define _GNU_SOURCE

#include "linux_internal.h"

#include <errno.h>
#include <limits.h>
#include <linux/can.h>
#include <linux/can/error.h>
#include <linux/can/netlink.h>
#include <linux/can/raw.h>
#include <linux/netlink.h>
#include <linux/rtnetlink.h>
#include <net/if.h>
#include <poll.h>
#include <stdio.h>
#include <string.h>
#include <linux/sockios.h>
#include <sys/ioctl.h>
#include <sys/socket.h>
#include <time.h>
#include <unistd.h>

/* Error classes that change the fault confinement state. Not CAN_ERR_PROT or
 * CAN_ERR_ACK: a broken bus reports one of those per failed frame (thousands
 * per second), and each would wake a lockstep tick wait. */
#define ERR_MASK (CAN_ERR_CRTL | CAN_ERR_BUSOFF | CAN_ERR_RESTARTED)

/* Static: one CAN controller per process, used from the main loop only. */
static struct {
    int fd;                        /* -1: closed */
    char ifname[IFNAMSIZ];
    int ifindex;
    bool controller;               /* link kind "can": a controller the driver can restart */
    pma_linux_ring_t rx;
    pma_linux_can_err_t err;
    uint32_t socket_drops;         /* SO_RXQ_OVFL: frames the socket dropped since it was opened */
    bool tick_armed;               /* lockstep tick started: tick frames count */
    uint16_t tick_id, tick_mask;
    int tick_dlc;                  /* required data length of a tick frame; -1: any */
    uint32_t ticks_pending;        /* tick frames read and not yet reported by a tick wait */
} can = {.fd = -1};

static bool is_tick(const pma_can_frame_t *f)
{
    return (f->id & can.tick_mask) == (can.tick_id & can.tick_mask) &&
           (can.tick_dlc < 0 || f->dlc == (uint8_t)can.tick_dlc);
}

/* Common checks of every CAN function. */
static int usable(void)
{
    if (!pma_linux_initialised()) return PMA_ERR_NOT_READY;
    if (can.fd < 0) return PMA_ERR_NOT_IMPLEMENTED; /* configured with no_can */
    return PMA_OK;
}

static void count_drops(struct msghdr *msg)
{
    for (struct cmsghdr *c = CMSG_FIRSTHDR(msg); c != NULL; c = CMSG_NXTHDR(msg, c)) {
        if (c->cmsg_level == SOL_SOCKET && c->cmsg_type == SO_RXQ_OVFL) {
            uint32_t total;
            memcpy(&total, CMSG_DATA(c), sizeof total);
            can.socket_drops = total; /* cumulative for this socket */
        }
    }
}

/* Takes one frame that the socket delivered. */
static void accept_frame(const struct can_frame *f, ssize_t bytes)
{
    if (bytes != (ssize_t)CAN_MTU) return; /* CAN FD: never delivered without CAN_RAW_FD_FRAMES */
    if (f->can_id & CAN_ERR_FLAG) {
        pma_linux_can_err_apply(&can.err, f->can_id, f->data);
        return;
    }
    /* The filters already keep extended and remote frames out (apply_filters) */
    if ((f->can_id & (CAN_EFF_FLAG | CAN_RTR_FLAG)) != 0 || f->len > PMA_CAN_DLC_MAX) return;
    pma_can_frame_t frame = {.id = (uint16_t)(f->can_id & CAN_SFF_MASK), .dlc = f->len};
    memcpy(frame.data, f->data, frame.dlc);
    (void)pma_linux_ring_push(&can.rx, &frame); /* the caller made room */
    if (can.tick_armed && is_tick(&frame)) can.ticks_pending++;
}

/* Reads what the socket holds into the ring, until the socket is empty or the
 * ring full. Returns how many frames (error frames included) it read, or
 * PMA_ERR_IO (message set) when the socket failed. */
static int pump(void)
{
    int read_count = 0;
    while (can.rx.count < PMA_HAL_LINUX_CAN_RX_DEPTH) {
        struct can_frame f;
        struct iovec iov = {.iov_base = &f, .iov_len = sizeof f};
        union {
            struct cmsghdr align;
            char buf[CMSG_SPACE(sizeof(uint32_t))];
        } ctrl;
        struct msghdr msg = {.msg_iov = &iov, .msg_iovlen = 1,
                             .msg_control = ctrl.buf, .msg_controllen = sizeof ctrl.buf};
        const ssize_t got = recvmsg(can.fd, &msg, MSG_DONTWAIT);
        if (got < 0) {
            if (errno == EAGAIN || errno == EWOULDBLOCK) break;
            if (errno == EINTR) continue;
            pma_linux_set_error("CAN interface %s: receive: %s", can.ifname, strerror(errno));
            return PMA_ERR_IO;
        }
        read_count++;
        count_drops(&msg);
        accept_frame(&f, got);
    }
    return read_count;
}

/* One accept-all filter for count 0: SocketCAN's empty list receives nothing. */
static int apply_filters(const pma_can_filter_t *filters, size_t count)
{
    /* EFF and RTR in every mask with those bits 0 in the id: only classic
     * 11-bit data frames pass, so the others never even wake the port. */
    struct can_filter kf[PMA_CAN_FILTERS_MAX];
    size_t n = count;
    if (count == 0) {
        kf[0].can_id = 0;
        kf[0].can_mask = CAN_EFF_FLAG | CAN_RTR_FLAG;
        n = 1;
    }
    for (size_t i = 0; i < count; ++i) {
        kf[i].can_id = filters[i].id;
        kf[i].can_mask = (canid_t)filters[i].mask | CAN_EFF_FLAG | CAN_RTR_FLAG;
    }
    if (setsockopt(can.fd, SOL_CAN_RAW, CAN_RAW_FILTER, kf, (socklen_t)(n * sizeof kf[0])) != 0) {
        pma_linux_set_error("CAN interface %s: CAN_RAW_FILTER: %s", can.ifname, strerror(errno));
        return PMA_ERR_IO;
    }
    return PMA_OK;
}

/* ------------------------------------------------------------ netlink -- */

/* Appends one netlink attribute; NULL when the buffer is too small. */
static struct rtattr *attr_add(struct nlmsghdr *n, size_t capacity, unsigned short type,
                               const void *data, size_t len)
{
    const size_t offset = NLMSG_ALIGN(n->nlmsg_len);
    const size_t attr_len = RTA_LENGTH(len);
    if (offset + RTA_ALIGN(attr_len) > capacity) return NULL;
    struct rtattr *a = (struct rtattr *)((char *)n + offset);
    a->rta_type = type;
    a->rta_len = (unsigned short)attr_len;
    if (len > 0) memcpy(RTA_DATA(a), data, len);
    n->nlmsg_len = (uint32_t)(offset + RTA_ALIGN(attr_len));
    return a;
}

static void attr_nest_end(struct nlmsghdr *n, struct rtattr *nest)
{
    nest->rta_len = (unsigned short)((char *)n + n->nlmsg_len - (char *)nest);
}

/* Sends one rtnetlink request for our interface and reads the first answer
 * into `ans`. rtnetlink handles a request while it is sent, so the answer is
 * queued when sendto() returns: reading it does not block. Returns the
 * answer's length or -errno. */
static ssize_t rtnl_exchange(struct nlmsghdr *req, void *ans, size_t capacity)
{
    const int s = socket(AF_NETLINK, SOCK_RAW | SOCK_CLOEXEC, NETLINK_ROUTE);
    if (s < 0) return -errno;
    struct sockaddr_nl kernel;
    memset(&kernel, 0, sizeof kernel);
    kernel.nl_family = AF_NETLINK;
    ssize_t got;
    if (sendto(s, req, req->nlmsg_len, 0, (const struct sockaddr *)&kernel, sizeof kernel) < 0) {
        got = -errno;
    } else {
        got = recv(s, ans, capacity, MSG_DONTWAIT);
        if (got < 0) got = -errno;
    }
    (void)close(s);
    return got;
}

/* Whether the interface is a CAN controller (link kind "can", which the CAN
 * driver framework gives every hardware controller) rather than "vcan",
 * "vxcan", ... that never go bus-off by themselves. Asked with RTM_GETLINK,
 * which needs no privileges. When the answer is unclear: a controller. */
static bool is_can_controller(void)
{
    union {
        struct nlmsghdr n;
        char buf[NLMSG_SPACE(sizeof(struct ifinfomsg))];
    } req;
    memset(&req, 0, sizeof req);
    req.n.nlmsg_len = NLMSG_LENGTH(sizeof(struct ifinfomsg));
    req.n.nlmsg_type = RTM_GETLINK;
    req.n.nlmsg_flags = NLM_F_REQUEST;
    req.n.nlmsg_seq = 1;
    struct ifinfomsg *ifi = NLMSG_DATA(&req.n);
    ifi->ifi_family = AF_UNSPEC;
    ifi->ifi_index = can.ifindex;
    static union {
        struct nlmsghdr n;
        char buf[16384]; /* one link's attributes, statistics included */
    } ans;
    const ssize_t got = rtnl_exchange(&req.n, &ans, sizeof ans);
    if (got < 0 || !NLMSG_OK(&ans.n, (size_t)got) || ans.n.nlmsg_type != RTM_NEWLINK) return true;
    int len = (int)IFLA_PAYLOAD(&ans.n);
    for (struct rtattr *a = IFLA_RTA(NLMSG_DATA(&ans.n)); RTA_OK(a, len); a = RTA_NEXT(a, len)) {
        if (a->rta_type != IFLA_LINKINFO) continue;
        int info_len = (int)RTA_PAYLOAD(a);
        for (struct rtattr *b = RTA_DATA(a); RTA_OK(b, info_len); b = RTA_NEXT(b, info_len)) {
            if (b->rta_type == IFLA_INFO_KIND) {
                return RTA_PAYLOAD(b) >= 4 && memcmp(RTA_DATA(b), "can", 4) == 0;
            }
        }
    }
    return true;
}

/* Closes what was opened and reports the failed step (what: "" for the
 * interface lookup) with errno and a hint. */
static int open_fail(const char *what)
{
    const int e = errno;
    const char *hint = "";
    if (e == EAFNOSUPPORT) {
        hint = " (this kernel has no SocketCAN: run the program where it has, e.g. through "
               "hil/with-vcan)";
    } else if (e == ENODEV && what[0] == '\0') {
        hint = " (`ip -details link show` lists the interfaces)";
    } else if (e == ENODEV) {
        hint = " (not a CAN interface?)";
    }
    pma_linux_set_error("CAN interface %s: %s%s%s%s", can.ifname, what, what[0] ? ": " : "",
                        strerror(e), hint);
    pma_linux_can_close();
    return PMA_ERR_IO;
}

int pma_linux_can_open(const char *ifname, uint16_t tick_id, uint16_t tick_mask, int tick_dlc)
{
    pma_linux_can_close();
    (void)snprintf(can.ifname, sizeof can.ifname, "%s", ifname); /* length checked by the caller */
    can.tick_id = tick_id;
    can.tick_mask = tick_mask;
    can.tick_dlc = tick_dlc;

    can.fd = socket(PF_CAN, SOCK_RAW | SOCK_NONBLOCK | SOCK_CLOEXEC, CAN_RAW);
    if (can.fd < 0) return open_fail("socket(PF_CAN)");

    struct ifreq ifr;
    memset(&ifr, 0, sizeof ifr);
    memcpy(ifr.ifr_name, can.ifname, sizeof can.ifname);
    if (ioctl(can.fd, SIOCGIFINDEX, &ifr) != 0) return open_fail("");
    can.ifindex = ifr.ifr_ifindex;
    can.controller = is_can_controller();
    if (ioctl(can.fd, SIOCGIFFLAGS, &ifr) != 0) return open_fail("SIOCGIFFLAGS");
    if ((ifr.ifr_flags & IFF_UP) == 0) {
        pma_linux_set_error("CAN interface %s is down (bring it up: `ip link set %s up`, for a "
                            "controller with its bit rate: `ip link set %s up type can bitrate "
                            "1000000`)", can.ifname, can.ifname, can.ifname);
        pma_linux_can_close();
        return PMA_ERR_IO;
    }

    const can_err_mask_t err_mask = ERR_MASK;
    if (setsockopt(can.fd, SOL_CAN_RAW, CAN_RAW_ERR_FILTER, &err_mask, sizeof err_mask) != 0) {
        return open_fail("CAN_RAW_ERR_FILTER");
    }
    const int on = 1;
    if (setsockopt(can.fd, SOL_SOCKET, SO_RXQ_OVFL, &on, sizeof on) != 0) {
        return open_fail("SO_RXQ_OVFL");
    }
    /* A receive buffer for bursts: a sender on the same CPU (a flood, vcan) can queue
     * thousands of frames in one time slice before this process runs, and the
     * default buffer (about 200 frames) would drop the sensor frames among them. A
     * controller's FIFO plays this part on a board. SO_RCVBUFFORCE needs
     * CAP_NET_ADMIN; without it SO_RCVBUF, up to net.core.rmem_max. Best effort. */
    const int rcvbuf = PMA_HAL_LINUX_CAN_RCVBUF_BYTES;
    if (setsockopt(can.fd, SOL_SOCKET, SO_RCVBUFFORCE, &rcvbuf, sizeof rcvbuf) != 0) {
        (void)setsockopt(can.fd, SOL_SOCKET, SO_RCVBUF, &rcvbuf, sizeof rcvbuf);
    }
    if (apply_filters(NULL, 0) != PMA_OK) {
        pma_linux_can_close();
        return PMA_ERR_IO;
    }
    struct sockaddr_can addr;
    memset(&addr, 0, sizeof addr);
    addr.can_family = AF_CAN;
    addr.can_ifindex = can.ifindex;
    if (bind(can.fd, (const struct sockaddr *)&addr, sizeof addr) != 0) {
        return open_fail("bind");
    }
    return PMA_OK;
}

void pma_linux_can_close(void)
{
    if (can.fd >= 0) (void)close(can.fd);
    can.fd = -1;
    pma_linux_ring_clear(&can.rx);
    pma_linux_can_err_reset(&can.err);
    can.socket_drops = 0;
    can.tick_armed = false;
    can.ticks_pending = 0;
}

void pma_linux_can_flush(uint32_t max_us)
{
    if (can.fd < 0) return;
    const uint64_t deadline_us = pma_hal_time_us() + max_us;
    int unsent = 0;
    /* SIOCOUTQ: bytes still in the socket's send queue (the interface has not
     * taken them); vcan takes every frame at write() */
    while (ioctl(can.fd, SIOCOUTQ, &unsent) == 0 && unsent > 0 && pma_hal_time_us() < deadline_us) {
        const struct timespec ms = {.tv_sec = 0, .tv_nsec = 1000000L};
        (void)nanosleep(&ms, NULL);
    }
}

void pma_linux_can_tick_arm(void)
{
    /* Already armed (the tick restarted with a new period): the frames in the
     * ring were counted when they arrived; counting them again would grant
     * ticks twice. */
    if (can.tick_armed) return;
    /* Tick frames the application has not received yet count too: the
     * simulator may have sent the first sample before the tick started
     * (and it then waits for the reply to it). */
    can.ticks_pending = 0;
    for (uint32_t i = 0; i < can.rx.count; ++i) {
        if (is_tick(&can.rx.slot[(can.rx.head + i) % PMA_HAL_LINUX_CAN_RX_DEPTH])) {
            can.ticks_pending++;
        }
    }
    can.tick_armed = true;
}

void pma_linux_can_tick_disarm(void)
{
    can.tick_armed = false;
    can.ticks_pending = 0;
}

static bool take_tick(void)
{
    if (can.ticks_pending == 0) return false;
    can.ticks_pending--;
    return true;
}

int pma_linux_can_tick_wait(uint32_t idle_ms)
{
    if (take_tick()) return PMA_OK; /* arrived earlier: served at once */
    int n = pump();
    if (n < 0) return n;
    if (take_tick()) return PMA_OK;
    /* Other frames came in (the loop handles them), or the ring is full and
     * nothing more can be read until the loop drains it. */
    if (n > 0 || can.rx.count == PMA_HAL_LINUX_CAN_RX_DEPTH) return PMA_ERR_EMPTY;

    struct pollfd p = {.fd = can.fd, .events = POLLIN, .revents = 0};
    const int r = poll(&p, 1, idle_ms > (uint32_t)INT_MAX ? INT_MAX : (int)idle_ms);
    if (r < 0) {
        if (errno == EINTR) return PMA_ERR_EMPTY;
        pma_linux_set_error("CAN interface %s: poll: %s", can.ifname, strerror(errno));
        return PMA_ERR_IO;
    }
    if (r == 0) return PMA_ERR_EMPTY; /* idle: the loop still serves commands */
    n = pump();
    if (n < 0) return n;
    return take_tick() ? PMA_OK : PMA_ERR_EMPTY;
}

/* ---------------------------------------------------------- pma/hal.h -- */

int pma_hal_can_send(const pma_can_frame_t *frame)
{
    if (frame == NULL) return PMA_ERR_NULL;
    int rc = usable();
    if (rc != PMA_OK) return rc;
    if (frame->id > PMA_CAN_ID_MAX || frame->dlc > PMA_CAN_DLC_MAX) return PMA_ERR_RANGE;
    rc = pump(); /* a bus-off report may be waiting */
    if (rc < 0) return rc;
    if (can.err.bus_off) return PMA_ERR_BUS_OFF;

    struct can_frame f;
    memset(&f, 0, sizeof f);
    f.can_id = frame->id;
    f.len = frame->dlc;
    memcpy(f.data, frame->data, frame->dlc);
    const ssize_t w = write(can.fd, &f, sizeof f);
    if (w == (ssize_t)sizeof f) return PMA_OK;
    if (w < 0 && (errno == EAGAIN || errno == EWOULDBLOCK || errno == ENOBUFS)) {
        /* EAGAIN: the socket's send buffer is full of frames the interface
         * has not taken; ENOBUFS: the interface queue (qdisc) dropped it.
         * Either way nothing was queued. */
        pma_linux_set_error("CAN interface %s: TX full (%s: %s)", can.ifname,
                            errno == ENOBUFS ? "ENOBUFS" : "EAGAIN", strerror(errno));
        return PMA_ERR_FULL;
    }
    pma_linux_set_error("CAN interface %s: write: %s", can.ifname,
                        w < 0 ? strerror(errno) : "short write");
    return PMA_ERR_IO;
}

int pma_hal_can_recv(pma_can_frame_t *frame)
{
    if (frame == NULL) return PMA_ERR_NULL;
    const int rc = usable();
    if (rc != PMA_OK) return rc;
    if (can.rx.count == 0) {
        const int n = pump();
        if (n < 0) return n;
    }
    return pma_linux_ring_pop(&can.rx, frame) ? PMA_OK : PMA_ERR_EMPTY;
}

int pma_hal_can_set_filters(const pma_can_filter_t *filters, size_t count)
{
    const int rc = usable();
    if (rc != PMA_OK) return rc;
    if (count > PMA_CAN_FILTERS_MAX) return PMA_ERR_RANGE;
    if (count > 0 && filters == NULL) return PMA_ERR_NULL;
    for (size_t i = 0; i < count; ++i) {
        if (filters[i].id > PMA_CAN_ID_MAX || filters[i].mask > PMA_CAN_ID_MAX) {
            return PMA_ERR_RANGE;
        }
    }
    return apply_filters(filters, count);
}

int pma_hal_can_status(pma_can_status_t *status)
{
    if (status == NULL) return PMA_ERR_NULL;
    int rc = usable();
    if (rc != PMA_OK) return rc;
    rc = pump();
    if (rc < 0) return rc;
    status->tec = can.err.tec;
    status->rec = can.err.rec;
    status->state = pma_linux_can_err_state(&can.err);
    status->rx_overruns = can.socket_drops + can.err.controller_rx_overflows;
    return PMA_OK;
}

/* ---------------------------------------------------- bus-off recovery -- */

/* What `ip link set <if> type can restart` does: asks the CAN driver to
 * restart a bus-off controller (RTM_NEWLINK, IFLA_CAN_RESTART). Returns 0 or
 * the errno of the kernel's answer. The kernel handles the request while we
 * send it, so its answer is already queued when we read it. */
static int request_restart(void)
{
    union {
        struct nlmsghdr n;
        char buf[NLMSG_SPACE(sizeof(struct ifinfomsg)) + 64];
    } req;
    memset(&req, 0, sizeof req);
    req.n.nlmsg_len = NLMSG_LENGTH(sizeof(struct ifinfomsg));
    req.n.nlmsg_type = RTM_NEWLINK;
    req.n.nlmsg_flags = NLM_F_REQUEST | NLM_F_ACK;
    req.n.nlmsg_seq = 1;
    struct ifinfomsg *ifi = NLMSG_DATA(&req.n);
    ifi->ifi_family = AF_UNSPEC;
    ifi->ifi_index = can.ifindex;
    const uint32_t one = 1;
    struct rtattr *info = attr_add(&req.n, sizeof req, IFLA_LINKINFO, NULL, 0);
    struct rtattr *data = NULL;
    if (info != NULL && attr_add(&req.n, sizeof req, IFLA_INFO_KIND, "can", 4) != NULL) {
        data = attr_add(&req.n, sizeof req, IFLA_INFO_DATA, NULL, 0);
    }
    if (data == NULL || attr_add(&req.n, sizeof req, IFLA_CAN_RESTART, &one, sizeof one) == NULL) {
        return ENOBUFS; /* cannot happen: the buffer is sized for these attributes */
    }
    attr_nest_end(&req.n, data);
    attr_nest_end(&req.n, info);
    union {
        struct nlmsghdr n;
        char buf[512];
    } ans;
    const ssize_t got = rtnl_exchange(&req.n, &ans, sizeof ans);
    if (got == -EAGAIN) return 0; /* no answer (yet): taken as sent */
    if (got < 0) return (int)-got;
    if ((size_t)got >= NLMSG_LENGTH(sizeof(struct nlmsgerr)) && ans.n.nlmsg_type == NLMSG_ERROR) {
        const struct nlmsgerr *e = NLMSG_DATA(&ans.n);
        return -e->error; /* 0: acknowledged */
    }
    return 0;
}

/* Bus-off on Linux belongs to the kernel's CAN driver: it restarts the
 * controller by itself when the interface has `restart-ms N`, or on a
 * netlink restart request (needs CAP_NET_ADMIN) when restart-ms is 0, and
 * reports it with a CAN_ERR_RESTARTED error frame. The port keeps bus-off
 * latched until the application calls this, as the HAL contract says:
 * - an interface that is no CAN controller (link kind "vcan", "vxcan": it
 *   never goes bus-off by itself, only through injected error frames):
 *   there is nothing to restart, the latched state is cleared now;
 * - the driver already restarted (restart-ms): recovered now;
 * - otherwise the port sends the netlink restart request; the driver
 *   restarts the controller, and the CAN_ERR_RESTARTED frame that follows
 *   completes the recovery (poll pma_hal_can_status());
 * - EINVAL (restart-ms is set: the driver restarts on its own): waiting;
 * - EOPNOTSUPP (no CAN controller after all) and EBUSY (the driver says
 *   the controller is not bus-off): the latched state is cleared now;
 * - anything else (EPERM without CAP_NET_ADMIN): PMA_ERR_IO with the reason
 *   in pma_hal_linux_last_error(); a later call succeeds once the driver
 *   restarted by itself. */
int pma_hal_can_recover(void)
{
    int rc = usable();
    if (rc != PMA_OK) return rc;
    rc = pump();
    if (rc < 0) return rc;
    if (!can.err.bus_off || can.err.recovery_requested) return PMA_OK;
    if (can.err.kernel_restarted || !can.controller) {
        pma_linux_can_err_recovered(&can.err);
        return PMA_OK;
    }
    const int e = request_restart();
    if (e == 0 || e == EINVAL) {
        can.err.recovery_requested = true;
        return PMA_OK;
    }
    if (e == EOPNOTSUPP || e == EBUSY) {
        pma_linux_can_err_recovered(&can.err);
        return PMA_OK;
    }
    pma_linux_set_error("CAN interface %s: restart request refused: %s (needs CAP_NET_ADMIN; or "
                        "let the driver restart by itself: ip link set %s type can restart-ms "
                        "100)", can.ifname, strerror(e), can.ifname);
    return PMA_ERR_IO;
}
