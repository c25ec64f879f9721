/* SPDX-License-Identifier: Apache-2.0 */
/* Linux port, CAN on SocketCAN: needs a vcan interface, so CTest runs it
 * through hil/with-vcan and tests/hal/run_hal_linux_can.sh (which names the
 * interfaces in PMA_TEST_CAN_*). A second raw socket in the test, the
 * "peer", plays the rest of the bus. Built without ASan (it cannot run in
 * the User-Mode Linux guest: tests/hal/CMakeLists.txt), with UBSan.
 *
 * Nothing here waits for a time to pass: to show that a frame was NOT
 * received, the peer sends a frame that must be received after it (a
 * socket keeps frames in order); waits for frames that must come give up
 * after GIVE_UP_MS only so that a broken port fails instead of hanging. */
#define _GNU_SOURCE

#include "test_hal_linux.h"

#include <errno.h>
#include <fcntl.h>
#include <linux/can.h>
#include <linux/can/error.h>
#include <linux/can/raw.h>
#include <net/if.h>
#include <poll.h>
#include <sys/socket.h>
#include <time.h>

#define GIVE_UP_MS 5000
#define TICK_ID 0x100u

static const char *ifname;
static int peer = -1;

/* ------------------------------------------------------------- the peer -- */

/* Opens the peer's socket on interface `name` (`peer` is set at once, so
 * that tearDown closes it whatever fails after). */
static void open_peer(const char *name)
{
    const int s = socket(PF_CAN, SOCK_RAW | SOCK_CLOEXEC, CAN_RAW);
    TEST_ASSERT_TRUE(s >= 0);
    peer = s;
    const int on = 1; /* so that it can also send CAN FD frames */
    TEST_ASSERT_EQUAL_INT(0, setsockopt(s, SOL_CAN_RAW, CAN_RAW_FD_FRAMES, &on, sizeof on));
    struct sockaddr_can addr;
    memset(&addr, 0, sizeof addr);
    addr.can_family = AF_CAN;
    addr.can_ifindex = (int)if_nametoindex(name);
    TEST_ASSERT_TRUE(addr.can_ifindex > 0);
    TEST_ASSERT_EQUAL_INT(0, bind(s, (struct sockaddr *)&addr, sizeof addr));
}

/* A classic frame; can_id may carry CAN_EFF_FLAG, CAN_RTR_FLAG or CAN_ERR_FLAG. */
static void peer_send(uint32_t can_id, uint8_t len, const uint8_t *data)
{
    struct can_frame f;
    memset(&f, 0, sizeof f);
    f.can_id = can_id;
    f.len = len;
    if (data != NULL) memcpy(f.data, data, len);
    TEST_ASSERT_EQUAL_INT((ssize_t)sizeof f, write(peer, &f, sizeof f));
}

static void peer_send_id(uint32_t can_id)
{
    const uint8_t d[2] = {(uint8_t)(can_id >> 8), (uint8_t)can_id};
    peer_send(can_id, 2, d);
}

/* An error frame as a CAN driver sends it (linux/can/error.h). */
static void peer_send_error(uint32_t classes, uint8_t ctrl, uint8_t tec, uint8_t rec)
{
    const uint8_t d[8] = {0, ctrl, 0, 0, 0, 0, tec, rec};
    peer_send(CAN_ERR_FLAG | classes, CAN_ERR_DLC, d);
}

/* The next frame the port put on the bus. */
static void peer_recv(struct can_frame *f)
{
    struct pollfd p = {.fd = peer, .events = POLLIN, .revents = 0};
    TEST_ASSERT_EQUAL_INT(1, poll(&p, 1, GIVE_UP_MS));
    TEST_ASSERT_EQUAL_INT((ssize_t)sizeof *f, read(peer, f, sizeof *f));
}

/* ------------------------------------------------------------- the port -- */

static int init_port(const char *name, int lockstep)
{
    pma_hal_linux_config_t c = PMA_HAL_LINUX_CONFIG_INIT;
    c.can_ifname = name;
    c.lockstep = lockstep;
    c.tick_can_id = TICK_ID;
    c.tick_can_mask = 0x7FF;
    const pma_hal_config_t cfg = {.can_bitrate_bps = 0, .port = &c};
    const int rc = pma_hal_init(&cfg);
    if (rc != PMA_OK) printf("init: %s\n", pma_hal_linux_last_error());
    return rc;
}

static void sleep_ms(unsigned ms)
{
    const struct timespec ts = {.tv_sec = 0, .tv_nsec = (long)ms * 1000000L};
    (void)nanosleep(&ts, NULL);
}

/* The next frame from pma_hal_can_recv(), waiting for it to come. */
static void port_recv_wait(pma_can_frame_t *f)
{
    for (int waited_ms = 0; waited_ms < GIVE_UP_MS; ++waited_ms) {
        const int rc = pma_hal_can_recv(f);
        if (rc == PMA_OK) return;
        assert_status(rc, PMA_ERR_EMPTY);
        sleep_ms(1);
    }
    pma_test_fail("no frame within %d ms", GIVE_UP_MS);
}

static void expect_frame(uint16_t id)
{
    pma_can_frame_t f;
    port_recv_wait(&f);
    TEST_ASSERT_EQUAL_INT(id, f.id);
}

/* Every test: the peer on the test's interface. */
void setUp(void)
{
    open_peer(ifname);
}

/* The further fixture of the tests that start with the port up on the test's
 * interface: plain (lockstep 0) or in lockstep (1). */
static void port_up(int lockstep)
{
    assert_status(init_port(ifname, lockstep), PMA_OK);
}

/* After every test, also one that failed: the port down, the peer closed. */
void tearDown(void)
{
    pma_hal_deinit();
    if (peer >= 0) (void)close(peer);
    peer = -1;
}

/* --------------------------------------------------------------- tests -- */

static void test_init_errors(void)
{
    assert_status(init_port("vcan7", 0), PMA_ERR_IO);
    TEST_ASSERT_EQUAL_STRING("CAN interface vcan7: No such device (`ip -details link show` "
                             "lists the interfaces)",
                             pma_hal_linux_last_error());
    assert_status(init_port("lo", 0), PMA_ERR_IO);
    assert_contains(pma_hal_linux_last_error(),
                    "CAN interface lo: bind: No such device (not a CAN interface?)");
    const char *down = getenv("PMA_TEST_CAN_DOWN_IF");
    if (down != NULL) {
        assert_status(init_port(down, 0), PMA_ERR_IO);
        assert_contains(pma_hal_linux_last_error(), "is down");
    } else {
        printf("(no PMA_TEST_CAN_DOWN_IF: interface-down case not checked)\n");
    }
    pma_can_frame_t f;
    assert_status(pma_hal_can_recv(&f), PMA_ERR_NOT_READY);
    assert_status(init_port(ifname, 0), PMA_OK);
    TEST_ASSERT_EQUAL_STRING("", pma_hal_linux_last_error());
}

static void test_round_trip(void)
{
    port_up(0);
    const pma_can_frame_t out[3] = {{.id = 0x123, .dlc = 3, .data = {1, 2, 3}},
                                    {.id = 0x7FF, .dlc = 0, .data = {0}},
                                    {.id = 0x000, .dlc = 8, .data = {8, 7, 6, 5, 4, 3, 2, 1}}};
    for (int i = 0; i < 3; ++i) {
        assert_status(pma_hal_can_send(&out[i]), PMA_OK);
        struct can_frame f;
        peer_recv(&f);
        TEST_ASSERT_EQUAL_INT(out[i].id, f.can_id); /* no flags: classic, 11 bits, data */
        TEST_ASSERT_EQUAL_INT(out[i].dlc, f.len);
        if (out[i].dlc > 0) { /* Unity refuses to compare 0 bytes */
            TEST_ASSERT_EQUAL_MEMORY(out[i].data, f.data, out[i].dlc);
        }
    }
    /* refused frames are not sent: the next one the peer sees is the good one */
    pma_can_frame_t bad = {.id = 0x800, .dlc = 1, .data = {0}};
    assert_status(pma_hal_can_send(&bad), PMA_ERR_RANGE);
    bad.id = 0x10;
    bad.dlc = 9;
    assert_status(pma_hal_can_send(&bad), PMA_ERR_RANGE);
    assert_status(pma_hal_can_send(NULL), PMA_ERR_NULL);
    assert_status(pma_hal_can_send(&out[0]), PMA_OK);
    struct can_frame f;
    peer_recv(&f);
    TEST_ASSERT_EQUAL_INT(0x123, f.can_id);

    const uint8_t d[8] = {0xA0, 0xA1, 0xA2, 0xA3, 0xA4, 0xA5, 0xA6, 0xA7};
    peer_send(0x456, 8, d);
    pma_can_frame_t in;
    port_recv_wait(&in);
    TEST_ASSERT_EQUAL_INT(0x456, in.id);
    TEST_ASSERT_EQUAL_INT(8, in.dlc);
    TEST_ASSERT_EQUAL_MEMORY(d, in.data, 8);
    assert_status(pma_hal_can_recv(&in), PMA_ERR_EMPTY);
    assert_status(pma_hal_can_recv(NULL), PMA_ERR_NULL);

    pma_can_status_t st;
    assert_status(pma_hal_can_status(&st), PMA_OK);
    TEST_ASSERT_EQUAL_INT(PMA_CAN_ERROR_ACTIVE, st.state);
    TEST_ASSERT_EQUAL_INT(0, st.tec);
    TEST_ASSERT_EQUAL_INT(0, st.rec);
    TEST_ASSERT_EQUAL_INT(0, st.rx_overruns);
    assert_status(pma_hal_can_status(NULL), PMA_ERR_NULL);
    assert_status(pma_hal_can_recover(), PMA_OK); /* not bus-off: nothing to do */
}

static void test_filters(void)
{
    port_up(0);
    const pma_can_filter_t fl[2] = {{.id = 0x100, .mask = 0x7F0}, {.id = 0x321, .mask = 0x7FF}};
    assert_status(pma_hal_can_set_filters(fl, 2), PMA_OK);
    peer_send_id(0x105);
    peer_send_id(0x205);
    peer_send_id(0x321);
    peer_send_id(0x322);
    peer_send_id(0x10F);
    expect_frame(0x105);
    expect_frame(0x321);
    expect_frame(0x10F); /* 0x205 and 0x322, sent before it, never came */
    pma_can_frame_t f;
    assert_status(pma_hal_can_recv(&f), PMA_ERR_EMPTY);

    /* refused changes change nothing */
    pma_can_filter_t many[PMA_CAN_FILTERS_MAX + 1u];
    for (unsigned i = 0; i <= PMA_CAN_FILTERS_MAX; ++i) many[i] = fl[0];
    assert_status(pma_hal_can_set_filters(many, PMA_CAN_FILTERS_MAX + 1u), PMA_ERR_RANGE);
    const pma_can_filter_t bad_id = {.id = 0x800, .mask = 0x7FF};
    const pma_can_filter_t bad_mask = {.id = 0x100, .mask = 0x800};
    assert_status(pma_hal_can_set_filters(&bad_id, 1), PMA_ERR_RANGE);
    assert_status(pma_hal_can_set_filters(&bad_mask, 1), PMA_ERR_RANGE);
    assert_status(pma_hal_can_set_filters(NULL, 1), PMA_ERR_NULL);
    peer_send_id(0x205);
    peer_send_id(0x106);
    expect_frame(0x106);

    /* the most a port must support */
    for (unsigned i = 0; i < PMA_CAN_FILTERS_MAX; ++i) {
        many[i].id = (uint16_t)(0x400u + i);
        many[i].mask = 0x7FF;
    }
    assert_status(pma_hal_can_set_filters(many, PMA_CAN_FILTERS_MAX), PMA_OK);
    peer_send_id(0x106);
    peer_send_id(0x407);
    expect_frame(0x407);

    /* count 0: everything again (SocketCAN's empty list would be nothing) */
    assert_status(pma_hal_can_set_filters(NULL, 0), PMA_OK);
    peer_send_id(0x205);
    expect_frame(0x205);
    /* mask 0 accepts every id */
    const pma_can_filter_t any = {.id = 0x123, .mask = 0};
    assert_status(pma_hal_can_set_filters(&any, 1), PMA_OK);
    peer_send_id(0x7FF);
    expect_frame(0x7FF);
}

/* Extended, remote and CAN FD frames are not ours. */
static void test_classic_only(void)
{
    port_up(0);
    peer_send_id(CAN_EFF_FLAG | 0x123u);
    peer_send_id(CAN_EFF_FLAG | 0x1ABCDEFu);
    peer_send(CAN_RTR_FLAG | 0x123u, 0, NULL);
    struct canfd_frame fd;
    memset(&fd, 0, sizeof fd);
    fd.can_id = 0x124;
    fd.len = 12;
    fd.flags = CANFD_BRS;
    TEST_ASSERT_EQUAL_INT((ssize_t)sizeof fd, write(peer, &fd, sizeof fd));
    peer_send_id(0x125);
    expect_frame(0x125);
    pma_can_frame_t f;
    assert_status(pma_hal_can_recv(&f), PMA_ERR_EMPTY);
}

/* More frames than the ring holds, in two bursts that the socket can take:
 * every one arrives, in order, none counted as lost. */
static void test_rx_order(void)
{
    port_up(0);
    uint32_t sent = 0, got = 0;
    for (int burst = 0; burst < 2; ++burst) {
        for (int i = 0; i < 200; ++i, ++sent) {
            const uint8_t d[4] = {(uint8_t)sent, (uint8_t)(sent >> 8), 0, 0};
            peer_send(sent & 0x7FFu, 4, d);
        }
        const uint32_t take = burst == 0 ? 50u : 350u; /* the ring fills with the first burst */
        for (uint32_t i = 0; i < take; ++i, ++got) {
            pma_can_frame_t f;
            port_recv_wait(&f);
            TEST_ASSERT_EQUAL_INT(got & 0x7FFu, f.id);
            TEST_ASSERT_EQUAL_INT(got, f.data[0] | (f.data[1] << 8));
        }
    }
    pma_can_status_t st;
    assert_status(pma_hal_can_status(&st), PMA_OK);
    TEST_ASSERT_EQUAL_INT(0, st.rx_overruns);
}

/* The socket's receive buffer overflows while nobody reads: the frames lost
 * there are the rx_overruns. More frames than can fit: each one takes more
 * than its 16 bytes of the buffer. */
static void test_rx_overrun(void)
{
    port_up(0);
    int rcvbuf = 0; /* the port's socket has the same default size */
    socklen_t len = sizeof rcvbuf;
    TEST_ASSERT_EQUAL_INT(0, getsockopt(peer, SOL_SOCKET, SO_RCVBUF, &rcvbuf, &len));
    const uint32_t n = (uint32_t)rcvbuf / 16u + 64u;
    for (uint32_t i = 0; i < n; ++i) {
        const uint8_t d[4] = {(uint8_t)i, (uint8_t)(i >> 8), (uint8_t)(i >> 16), 0};
        peer_send(0x200, 4, d);
    }
    /* Drain what arrived, then a last frame with room for it: its arrival
     * carries the socket's drop count, and every frame sent before it has
     * been either received or lost by then. */
    uint32_t received = 0, last = 0;
    bool marker_sent = false;
    for (;;) {
        pma_can_frame_t f;
        const int rc = pma_hal_can_recv(&f);
        if (rc == PMA_ERR_EMPTY && !marker_sent) {
            peer_send_id(0x7FE);
            marker_sent = true;
            continue;
        }
        if (rc == PMA_ERR_EMPTY) {
            port_recv_wait(&f);
        } else {
            assert_status(rc, PMA_OK);
        }
        if (f.id == 0x7FE) break;
        const uint32_t seq = f.data[0] | (f.data[1] << 8) | ((uint32_t)f.data[2] << 16);
        TEST_ASSERT_TRUE(received == 0 || seq > last); /* in order, with gaps */
        last = seq;
        received++;
    }
    pma_can_status_t st;
    assert_status(pma_hal_can_status(&st), PMA_OK);
    printf("sent %u, received %u, rx_overruns %u\n", (unsigned)n, (unsigned)received,
           (unsigned)st.rx_overruns);
    TEST_ASSERT_LESS_THAN_UINT32(n, received);
    TEST_ASSERT_EQUAL_INT(n - received, st.rx_overruns);
}

static void tx_full(const char *env, const char *reason)
{
    const char *name = getenv(env);
    if (name == NULL) {
        static char why[128];
        (void)snprintf(why, sizeof why, "no %s: run through tests/hal/run_hal_linux_can.sh as root",
                       env);
        TEST_IGNORE_MESSAGE(why);
    }
    assert_status(init_port(name, 0), PMA_OK);
    const pma_can_frame_t f = {.id = 0x55, .dlc = 1, .data = {0x55}};
    uint32_t queued = 0;
    int rc;
    while ((rc = pma_hal_can_send(&f)) == PMA_OK && queued < 1000000u) queued++;
    printf("%s: %u frames queued, then %s\n", name, (unsigned)queued,
           pma_hal_linux_last_error());
    assert_status(rc, PMA_ERR_FULL);
    TEST_ASSERT_GREATER_THAN_UINT32(0, queued);
    assert_contains(pma_hal_linux_last_error(), reason);
    assert_status(pma_hal_can_send(&f), PMA_ERR_FULL); /* still full: nothing is sent */
}

/* The interface queue (qdisc) drops the frame: ENOBUFS. */
static void test_tx_full_interface_queue(void)
{
    tx_full("PMA_TEST_CAN_FULL_DROP_IF", "ENOBUFS");
}

/* The socket's send buffer holds frames the interface did not take: EAGAIN. */
static void test_tx_full_socket_buffer(void)
{
    tx_full("PMA_TEST_CAN_FULL_BUF_IF", "EAGAIN");
}

/* ------------------------------------------------------------ lockstep -- */

/* Calls tick_wait until it reports a tick, checking that every other result
 * is PMA_ERR_EMPTY; returns how many EMPTY came first. */
static int wait_tick(void)
{
    for (int empties = 0; empties < GIVE_UP_MS / 10; ++empties) {
        uint32_t late = 99;
        const int rc = pma_hal_tick_wait(&late);
        TEST_ASSERT_EQUAL_INT(0, late); /* never late in lockstep */
        if (rc == PMA_OK) return empties;
        assert_status(rc, PMA_ERR_EMPTY);
    }
    pma_test_fail("no tick");
    return -1;
}

static void test_lockstep_idle_and_other_frames(void)
{
    port_up(1);
    assert_status(pma_hal_tick_wait(NULL), PMA_ERR_NOT_READY);
    assert_status(pma_hal_tick_start(0), PMA_ERR_RANGE);
    assert_status(pma_hal_tick_start(1000), PMA_OK);
    uint32_t late = 99;
    assert_status(pma_hal_tick_wait(&late), PMA_ERR_EMPTY); /* idle: nothing on the bus */
    TEST_ASSERT_EQUAL_INT(0, late);
    /* another frame wakes it without a tick, and stays queued */
    peer_send_id(0x200);
    pma_can_frame_t f;
    for (int i = 0;; ++i) {
        TEST_ASSERT_LESS_THAN_INT(GIVE_UP_MS / 10, i);
        assert_status(pma_hal_tick_wait(NULL), PMA_ERR_EMPTY);
        if (pma_hal_can_recv(&f) == PMA_OK) break;
    }
    TEST_ASSERT_EQUAL_INT(0x200, f.id);
    /* an error frame too */
    peer_send_error(CAN_ERR_CRTL, CAN_ERR_CRTL_TX_WARNING, 0, 0);
    pma_can_status_t st;
    for (int i = 0;; ++i) {
        TEST_ASSERT_LESS_THAN_INT(GIVE_UP_MS / 10, i);
        assert_status(pma_hal_tick_wait(NULL), PMA_ERR_EMPTY);
        assert_status(pma_hal_can_status(&st), PMA_OK);
        if (st.tec == 96) break;
    }
}

static void test_lockstep_tick_frame(void)
{
    port_up(1);
    assert_status(pma_hal_tick_start(1000), PMA_OK);
    const uint8_t d[3] = {7, 8, 9};
    peer_send(TICK_ID, 3, d);
    (void)wait_tick();
    pma_can_frame_t f;
    assert_status(pma_hal_can_recv(&f), PMA_OK); /* the tick frame stayed queued */
    TEST_ASSERT_EQUAL_INT(TICK_ID, f.id);
    TEST_ASSERT_EQUAL_MEMORY(d, f.data, 3);
    assert_status(pma_hal_tick_wait(NULL), PMA_ERR_EMPTY); /* one tick per frame */
    /* a restart of the tick keeps lockstep */
    assert_status(pma_hal_tick_start(5000), PMA_OK);
    peer_send_id(TICK_ID);
    (void)wait_tick();
    expect_frame(TICK_ID);
}

/* Tick frames among others: one tick each, all frames kept in order. */
static void test_lockstep_ticks_queue_in_order(void)
{
    port_up(1);
    assert_status(pma_hal_tick_start(1000), PMA_OK);
    const uint16_t ids[5] = {0x200, TICK_ID, 0x201, TICK_ID, 0x202};
    for (int i = 0; i < 5; ++i) peer_send_id(ids[i]);
    (void)wait_tick();
    (void)wait_tick(); /* at once when the first wait already read both */
    /* no third tick, whatever else the waits still read */
    assert_status(pma_hal_tick_wait(NULL), PMA_ERR_EMPTY);
    assert_status(pma_hal_tick_wait(NULL), PMA_ERR_EMPTY);
    for (int i = 0; i < 5; ++i) expect_frame(ids[i]);
    pma_can_frame_t f;
    assert_status(pma_hal_can_recv(&f), PMA_ERR_EMPTY);
}

/* A tick frame that the loop received (pma_hal_can_recv) before it asked
 * for the tick is still a tick; one received before the tick started is not. */
static void test_lockstep_tick_taken_by_recv(void)
{
    port_up(1);
    peer_send_id(TICK_ID);
    expect_frame(TICK_ID);
    assert_status(pma_hal_tick_start(1000), PMA_OK);
    assert_status(pma_hal_tick_wait(NULL), PMA_ERR_EMPTY); /* it came before the start */
    peer_send_id(TICK_ID);
    expect_frame(TICK_ID);
    TEST_ASSERT_EQUAL_INT(0, wait_tick()); /* served at once */
    assert_status(pma_hal_tick_wait(NULL), PMA_ERR_EMPTY);
}

/* The tick id and mask select the tick frames. */
static void test_lockstep_tick_mask(void)
{
    pma_hal_linux_config_t c = PMA_HAL_LINUX_CONFIG_INIT;
    c.can_ifname = ifname;
    c.lockstep = 1;
    c.tick_can_id = 0x180;
    c.tick_can_mask = 0x780; /* 0x180..0x1FF */
    c.lockstep_idle_wake_ms = 1;
    const pma_hal_config_t cfg = {.can_bitrate_bps = 0, .port = &c};
    assert_status(pma_hal_init(&cfg), PMA_OK);
    assert_status(pma_hal_tick_start(1000), PMA_OK);
    peer_send_id(0x17F);
    peer_send_id(0x200);
    peer_send_id(0x1C5);
    (void)wait_tick();
    expect_frame(0x17F);
    expect_frame(0x200);
    expect_frame(0x1C5);
    assert_status(pma_hal_tick_wait(NULL), PMA_ERR_EMPTY);
}

/* ------------------------------------------------------- error frames -- */

/* Injects an error frame as a driver would send it, then waits until a data
 * frame sent after it has come: the error frame has been read by then. */
static void inject(uint32_t classes, uint8_t ctrl, uint8_t tec, uint8_t rec)
{
    peer_send_error(classes, ctrl, tec, rec);
    peer_send_id(0x010);
    expect_frame(0x010);
}

static pma_can_status_t status(void)
{
    pma_can_status_t st;
    assert_status(pma_hal_can_status(&st), PMA_OK);
    return st;
}

static void test_error_frames(void)
{
    port_up(0);
    /* error frames pass whatever the filters */
    const pma_can_filter_t only = {.id = 0x010, .mask = 0x7FF};
    assert_status(pma_hal_can_set_filters(&only, 1), PMA_OK);

    inject(CAN_ERR_CRTL | CAN_ERR_CNT, CAN_ERR_CRTL_TX_PASSIVE, 130, 5);
    pma_can_status_t st = status();
    TEST_ASSERT_EQUAL_INT(PMA_CAN_ERROR_PASSIVE, st.state);
    TEST_ASSERT_EQUAL_INT(130, st.tec);
    TEST_ASSERT_EQUAL_INT(5, st.rec);
    inject(CAN_ERR_CRTL | CAN_ERR_CNT, CAN_ERR_CRTL_ACTIVE, 10, 0);
    st = status();
    TEST_ASSERT_EQUAL_INT(PMA_CAN_ERROR_ACTIVE, st.state);
    TEST_ASSERT_EQUAL_INT(10, st.tec);
    inject(CAN_ERR_CRTL, CAN_ERR_CRTL_RX_PASSIVE, 0, 0); /* no counters: the state's level */
    st = status();
    TEST_ASSERT_EQUAL_INT(PMA_CAN_ERROR_PASSIVE, st.state);
    TEST_ASSERT_EQUAL_INT(128, st.rec);

    /* bus-off: nothing sent until recovered; on vcan recovery is immediate */
    inject(CAN_ERR_BUSOFF, 0, 0, 0);
    st = status();
    TEST_ASSERT_EQUAL_INT(PMA_CAN_BUS_OFF, st.state);
    TEST_ASSERT_EQUAL_INT(256, st.tec);
    const pma_can_frame_t f = {.id = 0x321, .dlc = 1, .data = {1}};
    assert_status(pma_hal_can_send(&f), PMA_ERR_BUS_OFF);
    assert_status(pma_hal_can_recover(), PMA_OK);
    st = status();
    TEST_ASSERT_EQUAL_INT(PMA_CAN_ERROR_ACTIVE, st.state);
    TEST_ASSERT_EQUAL_INT(0, st.tec);
    TEST_ASSERT_EQUAL_INT(0, st.rec);
    assert_status(pma_hal_can_send(&f), PMA_OK);
    struct can_frame back;
    peer_recv(&back);
    TEST_ASSERT_EQUAL_INT(0x321, back.can_id); /* the frame refused in bus-off never went out */

    /* the driver restarting by itself (restart-ms) does not end a latched bus-off */
    inject(CAN_ERR_BUSOFF, 0, 0, 0);
    inject(CAN_ERR_RESTARTED, 0, 0, 0);
    TEST_ASSERT_EQUAL_INT(PMA_CAN_BUS_OFF, status().state);
    assert_status(pma_hal_can_send(&f), PMA_ERR_BUS_OFF);
    assert_status(pma_hal_can_recover(), PMA_OK);
    TEST_ASSERT_EQUAL_INT(PMA_CAN_ERROR_ACTIVE, status().state);

    /* the controller lost frames */
    inject(CAN_ERR_CRTL, CAN_ERR_CRTL_RX_OVERFLOW, 0, 0);
    TEST_ASSERT_EQUAL_INT(1, status().rx_overruns);

    /* init starts afresh */
    inject(CAN_ERR_BUSOFF, 0, 0, 0);
    assert_status(init_port(ifname, 0), PMA_OK);
    st = status();
    TEST_ASSERT_EQUAL_INT(PMA_CAN_ERROR_ACTIVE, st.state);
    TEST_ASSERT_EQUAL_INT(0, st.rx_overruns);
}

int main(void)
{
    ifname = getenv("PMA_TEST_CAN_IF");
    if (ifname == NULL) ifname = "vcan0";
    printf("CAN interface: %s\n", ifname);
    UNITY_BEGIN();
    RUN_TEST(test_init_errors);
    RUN_TEST(test_round_trip);
    RUN_TEST(test_filters);
    RUN_TEST(test_classic_only);
    RUN_TEST(test_rx_order);
    RUN_TEST(test_rx_overrun);
    RUN_TEST(test_tx_full_interface_queue);
    RUN_TEST(test_tx_full_socket_buffer);
    RUN_TEST(test_lockstep_idle_and_other_frames);
    RUN_TEST(test_lockstep_tick_frame);
    RUN_TEST(test_lockstep_ticks_queue_in_order);
    RUN_TEST(test_lockstep_tick_taken_by_recv);
    RUN_TEST(test_lockstep_tick_mask);
    RUN_TEST(test_error_frames);
    return UNITY_END();
}
