/* SPDX-License-Identifier: Apache-2.0 */
/* Linux port without a CAN interface (runs on any host, under ASan): the
 * init rules and errors with their messages, the devices this port does not
 * have, and the pure parts of CAN: the RX ring and the decoding of SocketCAN
 * error frames (the vcan test, test_hal_linux_can.c, runs without ASan). */
#define _GNU_SOURCE

#include "test_hal_linux.h"

#include <fcntl.h>
#include <linux/can.h>
#include <linux/can/error.h>
#include <sys/file.h>

#include "linux_internal.h"

static char dir[256];  /* the test's directory; "" when it has none */
static int locker = -1; /* test_storage_errors: the other holder of the storage file */

/* The fixture of the tests of the port itself: a fresh directory for their
 * files. The pure tests (ring, error frames, reset-cause names) have none. */
static void make_dir(void)
{
    linux_test_mkdtemp(dir, sizeof dir);
}

/* After every test, also one that failed: the port down (a no-op for the
 * pure tests), the directory removed, the lock holder's file closed. */
void tearDown(void)
{
    pma_hal_deinit();
    if (dir[0] != '\0') linux_test_rmdir(dir);
    dir[0] = '\0';
    if (locker >= 0) (void)close(locker);
    locker = -1;
}

static pma_hal_linux_config_t no_can_config(void)
{
    pma_hal_linux_config_t c = PMA_HAL_LINUX_CONFIG_INIT;
    c.no_can = 1;
    return c;
}

static int init_with(const pma_hal_linux_config_t *c)
{
    const pma_hal_config_t cfg = {.can_bitrate_bps = 0, .port = c};
    return pma_hal_init(&cfg);
}

/* Every device function before init (and after deinit). */
static void check_not_ready(void)
{
    pma_can_frame_t f = {.id = 1, .dlc = 0, .data = {0}};
    pma_can_status_t st;
    pma_nvm_geometry_t g;
    uint8_t b[8] = {0};
    uint16_t raw;
    uint32_t late;
    assert_status(pma_hal_can_send(&f), PMA_ERR_NOT_READY);
    assert_status(pma_hal_can_recv(&f), PMA_ERR_NOT_READY);
    assert_status(pma_hal_can_set_filters(NULL, 0), PMA_ERR_NOT_READY);
    assert_status(pma_hal_can_status(&st), PMA_ERR_NOT_READY);
    assert_status(pma_hal_can_recover(), PMA_ERR_NOT_READY);
    assert_status(pma_hal_tick_start(1000), PMA_ERR_NOT_READY);
    assert_status(pma_hal_tick_wait(&late), PMA_ERR_NOT_READY);
    assert_status(pma_hal_nvm_geometry(&g), PMA_ERR_NOT_READY);
    assert_status(pma_hal_nvm_read(0, 0, b, 8), PMA_ERR_NOT_READY);
    assert_status(pma_hal_nvm_program(0, 0, b, 8), PMA_ERR_NOT_READY);
    assert_status(pma_hal_nvm_erase(0), PMA_ERR_NOT_READY);
    assert_status(pma_hal_adc_read(&raw), PMA_ERR_NOT_READY);
    assert_status(pma_hal_dac_write(0), PMA_ERR_NOT_READY);
}

static void test_not_ready_and_name(void)
{
    make_dir();
    TEST_ASSERT_EQUAL_STRING("linux", pma_hal_port_name());
    check_not_ready();
    TEST_ASSERT_GREATER_THAN_UINT64(0, pma_hal_time_us()); /* the clock works before init */
    pma_hal_watchdog_kick();            /* not started: does nothing */
    assert_status(pma_hal_watchdog_start(0), PMA_ERR_RANGE);
    assert_status(pma_hal_watchdog_start(PMA_HAL_LINUX_WATCHDOG_MAX_MS + 1u), PMA_ERR_RANGE);
}

static void test_no_can_devices(void)
{
    make_dir();
    const pma_hal_linux_config_t c = no_can_config();
    assert_status(init_with(&c), PMA_OK);
    TEST_ASSERT_EQUAL_STRING("", pma_hal_linux_last_error());
    pma_can_frame_t f = {.id = 1, .dlc = 0, .data = {0}};
    pma_can_status_t st;
    assert_status(pma_hal_can_send(&f), PMA_ERR_NOT_IMPLEMENTED);
    assert_status(pma_hal_can_recv(&f), PMA_ERR_NOT_IMPLEMENTED);
    assert_status(pma_hal_can_set_filters(NULL, 0), PMA_ERR_NOT_IMPLEMENTED);
    assert_status(pma_hal_can_status(&st), PMA_ERR_NOT_IMPLEMENTED);
    assert_status(pma_hal_can_recover(), PMA_ERR_NOT_IMPLEMENTED);
    /* no converters on a host: bridged over CAN */
    uint16_t raw;
    assert_status(pma_hal_adc_read(&raw), PMA_ERR_NOT_IMPLEMENTED);
    assert_status(pma_hal_adc_read(NULL), PMA_ERR_NULL);
    assert_status(pma_hal_dac_write(100), PMA_ERR_NOT_IMPLEMENTED);
    /* no storage_path: no NVM */
    pma_nvm_geometry_t g;
    uint8_t b[8] = {0};
    assert_status(pma_hal_nvm_geometry(&g), PMA_ERR_NOT_IMPLEMENTED);
    assert_status(pma_hal_nvm_read(0, 0, b, 8), PMA_ERR_NOT_IMPLEMENTED);
    assert_status(pma_hal_nvm_program(0, 0, b, 8), PMA_ERR_NOT_IMPLEMENTED);
    assert_status(pma_hal_nvm_erase(0), PMA_ERR_NOT_IMPLEMENTED);
    pma_hal_deinit();
    check_not_ready();
}

/* A missing interface: on a kernel without SocketCAN (this project's build
 * machines) socket(PF_CAN) itself fails; with SocketCAN the name is unknown.
 * Either way the message names the interface and the reason. */
static void test_missing_interface(void)
{
    make_dir();
    pma_hal_linux_config_t c = PMA_HAL_LINUX_CONFIG_INIT;
    c.can_ifname = "vcan7";
    assert_status(init_with(&c), PMA_ERR_IO);
    const char *msg = pma_hal_linux_last_error();
    printf("message: %s\n", msg);
    assert_contains(msg, "CAN interface vcan7: ");
    if (strstr(msg, "No such device") == NULL) {
        assert_contains(msg, "Address family not supported by protocol");
        assert_contains(msg, "no SocketCAN");
    }
    check_not_ready(); /* a failed init leaves the port uninitialised */
}

/* pma_hal_init(NULL): the defaults, i.e. CAN on vcan0 (and nothing else). */
static void test_null_config_is_vcan0(void)
{
    make_dir();
    const int rc = pma_hal_init(NULL);
    if (rc == PMA_OK) { /* a host with SocketCAN and a vcan0 */
        TEST_ASSERT_EQUAL_STRING("", pma_hal_linux_last_error());
        return;
    }
    assert_status(rc, PMA_ERR_IO);
    assert_contains(pma_hal_linux_last_error(), "CAN interface vcan0: ");
}

static void test_config_errors(void)
{
    make_dir();
    pma_hal_linux_config_t c = PMA_HAL_LINUX_CONFIG_INIT;
    c.can_ifname = NULL;
    assert_status(init_with(&c), PMA_ERR_NULL);
    assert_contains(pma_hal_linux_last_error(), "can_ifname");
    c.can_ifname = "a_name_too_long_for_linux";
    assert_status(init_with(&c), PMA_ERR_RANGE);
    assert_contains(pma_hal_linux_last_error(), "a_name_too_long_for_linux");
    c.can_ifname = "";
    assert_status(init_with(&c), PMA_ERR_RANGE);

    c = no_can_config();
    c.lockstep = 1;
    assert_status(init_with(&c), PMA_ERR_RANGE);
    assert_contains(pma_hal_linux_last_error(), "lockstep");
    c = no_can_config();
    c.tick_can_mask = 0x800;
    assert_status(init_with(&c), PMA_ERR_RANGE);

    char path[300];
    (void)snprintf(path, sizeof path, "%s/nvm.bin", dir);
    c = no_can_config();
    c.storage_path = path;
    c.nvm_block_size = 12; /* not a multiple of the program size */
    assert_status(init_with(&c), PMA_ERR_RANGE);
    assert_contains(pma_hal_linux_last_error(), "multiple of 8");
    c.nvm_block_size = 1u << 20;
    c.nvm_block_count = 65; /* above the 64 MiB limit */
    assert_status(init_with(&c), PMA_ERR_RANGE);
    c = no_can_config();
    c.storage_path = path;
    c.nvm_cut_permille = 1001;
    assert_status(init_with(&c), PMA_ERR_RANGE);
    c.nvm_cut_permille = 0;
    c.nvm_cut_after_ops = -2;
    assert_status(init_with(&c), PMA_ERR_RANGE);
    TEST_ASSERT_EQUAL_INT(-1, access(path, F_OK)); /* nothing was created */
    check_not_ready();
}

static void test_storage_errors(void)
{
    make_dir();
    char path[300];
    pma_hal_linux_config_t c = no_can_config();
    c.storage_path = path;

    (void)snprintf(path, sizeof path, "%s/no/such/dir/nvm.bin", dir);
    assert_status(init_with(&c), PMA_ERR_IO);
    assert_contains(pma_hal_linux_last_error(), path);
    assert_contains(pma_hal_linux_last_error(), "No such file or directory");

    (void)snprintf(path, sizeof path, "%s", dir); /* a directory */
    assert_status(init_with(&c), PMA_ERR_IO);
    assert_contains(pma_hal_linux_last_error(), "storage file");

    /* another process (here: another open file description) holds it */
    (void)snprintf(path, sizeof path, "%s/nvm.bin", dir);
    assert_status(init_with(&c), PMA_OK); /* creates it */
    pma_hal_deinit();
    locker = open(path, O_RDWR | O_CLOEXEC);
    TEST_ASSERT_TRUE(locker >= 0);
    TEST_ASSERT_EQUAL_INT(0, flock(locker, LOCK_EX | LOCK_NB));
    assert_status(init_with(&c), PMA_ERR_IO);
    assert_contains(pma_hal_linux_last_error(), "in use by another process");
    (void)close(locker);
    locker = -1;
    assert_status(init_with(&c), PMA_OK);
}

/* Re-initialising keeps working and a failed re-init leaves nothing open. */
static void test_reinit(void)
{
    make_dir();
    pma_hal_linux_config_t c = no_can_config();
    assert_status(init_with(&c), PMA_OK);
    assert_status(pma_hal_tick_start(1000), PMA_OK);
    assert_status(init_with(&c), PMA_OK); /* again: the tick is stopped */
    assert_status(pma_hal_tick_wait(NULL), PMA_ERR_NOT_READY);
    c.nvm_block_size = 3;
    c.storage_path = "unused";
    assert_status(init_with(&c), PMA_ERR_RANGE);
    check_not_ready();
}

/* ------------------------------------------------------------ RX ring -- */

static void test_ring_order_and_capacity(void)
{
    static pma_linux_ring_t r;
    pma_linux_ring_clear(&r);
    pma_can_frame_t f = {.id = 0, .dlc = 2, .data = {0}};
    /* wraps around several times, in order */
    uint32_t next_in = 0, next_out = 0;
    for (int round = 0; round < 5; ++round) {
        while (true) {
            f.id = (uint16_t)(next_in & 0x7FFu);
            f.data[0] = (uint8_t)next_in;
            if (!pma_linux_ring_push(&r, &f)) break;
            next_in++;
        }
        TEST_ASSERT_EQUAL_INT(PMA_HAL_LINUX_CAN_RX_DEPTH, r.count);
        for (uint32_t i = 0; i < PMA_HAL_LINUX_CAN_RX_DEPTH / 2u + (uint32_t)round; ++i) {
            pma_can_frame_t out;
            TEST_ASSERT_TRUE(pma_linux_ring_pop(&r, &out));
            TEST_ASSERT_EQUAL_INT(next_out & 0x7FFu, out.id);
            TEST_ASSERT_EQUAL_INT((uint8_t)next_out, out.data[0]);
            next_out++;
        }
    }
    pma_can_frame_t out;
    while (pma_linux_ring_pop(&r, &out)) {
        TEST_ASSERT_EQUAL_INT(next_out & 0x7FFu, out.id);
        next_out++;
    }
    TEST_ASSERT_EQUAL_INT(next_in, next_out);
    TEST_ASSERT_FALSE(pma_linux_ring_pop(&r, &out));
}

/* ------------------------------------------------------- error frames -- */

static void apply(pma_linux_can_err_t *e, uint32_t id, uint8_t d1, uint8_t tec, uint8_t rec)
{
    const uint8_t data[8] = {0, d1, 0, 0, 0, 0, tec, rec};
    pma_linux_can_err_apply(e, id, data);
}

static void test_error_frames_counters(void)
{
    pma_linux_can_err_t e;
    pma_linux_can_err_reset(&e);
    TEST_ASSERT_EQUAL_INT(PMA_CAN_ERROR_ACTIVE, pma_linux_can_err_state(&e));

    /* a data frame is no error report */
    apply(&e, 0x123, CAN_ERR_CRTL_TX_PASSIVE, 200, 0);
    TEST_ASSERT_EQUAL_INT(PMA_CAN_ERROR_ACTIVE, pma_linux_can_err_state(&e));

    /* counters given by CAN_ERR_CNT */
    apply(&e, CAN_ERR_FLAG | CAN_ERR_CRTL | CAN_ERR_CNT, CAN_ERR_CRTL_TX_PASSIVE, 130, 5);
    TEST_ASSERT_EQUAL_INT(130, e.tec);
    TEST_ASSERT_EQUAL_INT(5, e.rec);
    TEST_ASSERT_EQUAL_INT(PMA_CAN_ERROR_PASSIVE, pma_linux_can_err_state(&e));
    apply(&e, CAN_ERR_FLAG | CAN_ERR_CRTL | CAN_ERR_CNT, CAN_ERR_CRTL_ACTIVE, 20, 3);
    TEST_ASSERT_EQUAL_INT(20, e.tec);
    TEST_ASSERT_EQUAL_INT(PMA_CAN_ERROR_ACTIVE, pma_linux_can_err_state(&e));

    /* without counters: the state's nearest value */
    pma_linux_can_err_reset(&e);
    apply(&e, CAN_ERR_FLAG | CAN_ERR_CRTL, CAN_ERR_CRTL_RX_WARNING, 0, 0);
    TEST_ASSERT_EQUAL_INT(96, e.rec);
    /* warning is active */
    TEST_ASSERT_EQUAL_INT(PMA_CAN_ERROR_ACTIVE, pma_linux_can_err_state(&e));
    apply(&e, CAN_ERR_FLAG | CAN_ERR_CRTL, CAN_ERR_CRTL_RX_PASSIVE, 0, 0);
    TEST_ASSERT_EQUAL_INT(128, e.rec);
    TEST_ASSERT_EQUAL_INT(PMA_CAN_ERROR_PASSIVE, pma_linux_can_err_state(&e));
    apply(&e, CAN_ERR_FLAG | CAN_ERR_CRTL, CAN_ERR_CRTL_TX_PASSIVE | CAN_ERR_CRTL_RX_WARNING, 0, 0);
    TEST_ASSERT_EQUAL_INT(128, e.tec);
    TEST_ASSERT_EQUAL_INT(127, e.rec); /* down from passive to warning */
    apply(&e, CAN_ERR_FLAG | CAN_ERR_CRTL, CAN_ERR_CRTL_TX_WARNING, 0, 0);
    TEST_ASSERT_EQUAL_INT(127, e.tec);
    TEST_ASSERT_EQUAL_INT(PMA_CAN_ERROR_ACTIVE, pma_linux_can_err_state(&e));
    apply(&e, CAN_ERR_FLAG | CAN_ERR_CRTL, CAN_ERR_CRTL_ACTIVE, 0, 0);
    TEST_ASSERT_EQUAL_INT(95, e.tec);
    TEST_ASSERT_EQUAL_INT(95, e.rec);
    TEST_ASSERT_EQUAL_INT(PMA_CAN_ERROR_ACTIVE, pma_linux_can_err_state(&e));

    /* controller RX overflow: frames lost before the socket */
    apply(&e, CAN_ERR_FLAG | CAN_ERR_CRTL, CAN_ERR_CRTL_RX_OVERFLOW, 0, 0);
    apply(&e, CAN_ERR_FLAG | CAN_ERR_CRTL, CAN_ERR_CRTL_RX_OVERFLOW, 0, 0);
    TEST_ASSERT_EQUAL_INT(2, e.controller_rx_overflows);
    TEST_ASSERT_EQUAL_INT(95, e.tec); /* no state bits: counters unchanged */
}

static void test_error_frames_bus_off(void)
{
    pma_linux_can_err_t e;
    pma_linux_can_err_reset(&e);
    apply(&e, CAN_ERR_FLAG | CAN_ERR_BUSOFF, 0, 0, 0);
    TEST_ASSERT_TRUE(e.bus_off);
    TEST_ASSERT_EQUAL_INT(256, e.tec);
    TEST_ASSERT_EQUAL_INT(PMA_CAN_BUS_OFF, pma_linux_can_err_state(&e));
    /* counters and state reports do not move a latched bus-off */
    apply(&e, CAN_ERR_FLAG | CAN_ERR_CRTL | CAN_ERR_CNT, CAN_ERR_CRTL_ACTIVE, 0, 0);
    TEST_ASSERT_EQUAL_INT(256, e.tec);
    TEST_ASSERT_EQUAL_INT(PMA_CAN_BUS_OFF, pma_linux_can_err_state(&e));
    /* the driver restarted (restart-ms) before the application asked: latched */
    apply(&e, CAN_ERR_FLAG | CAN_ERR_RESTARTED, 0, 0, 0);
    TEST_ASSERT_TRUE(e.kernel_restarted);
    TEST_ASSERT_EQUAL_INT(PMA_CAN_BUS_OFF, pma_linux_can_err_state(&e));
    pma_linux_can_err_recovered(&e);
    TEST_ASSERT_EQUAL_INT(PMA_CAN_ERROR_ACTIVE, pma_linux_can_err_state(&e));
    TEST_ASSERT_EQUAL_INT(0, e.tec);
    TEST_ASSERT_FALSE(e.kernel_restarted);

    /* asked first, then the driver's restart completes it */
    apply(&e, CAN_ERR_FLAG | CAN_ERR_BUSOFF, 0, 0, 0);
    e.recovery_requested = true;
    apply(&e, CAN_ERR_FLAG | CAN_ERR_CRTL, CAN_ERR_CRTL_ACTIVE, 0, 0);
    TEST_ASSERT_EQUAL_INT(PMA_CAN_BUS_OFF, pma_linux_can_err_state(&e));
    apply(&e, CAN_ERR_FLAG | CAN_ERR_RESTARTED, 0, 0, 0);
    TEST_ASSERT_EQUAL_INT(PMA_CAN_ERROR_ACTIVE, pma_linux_can_err_state(&e));
    TEST_ASSERT_FALSE(e.recovery_requested);
    TEST_ASSERT_EQUAL_INT(0, e.tec);
    TEST_ASSERT_EQUAL_INT(0, e.rec);

    /* a restart report while not bus-off: counters start from 0 */
    apply(&e, CAN_ERR_FLAG | CAN_ERR_CRTL | CAN_ERR_CNT, CAN_ERR_CRTL_TX_PASSIVE, 140, 7);
    apply(&e, CAN_ERR_FLAG | CAN_ERR_RESTARTED, 0, 0, 0);
    TEST_ASSERT_EQUAL_INT(0, e.tec);
    TEST_ASSERT_EQUAL_INT(0, e.rec);
}

static void test_reset_cause_names(void)
{
    TEST_ASSERT_EQUAL_INT(PMA_RESET_POWER_ON, pma_linux_reset_cause_parse(NULL));
    TEST_ASSERT_EQUAL_INT(PMA_RESET_WATCHDOG, pma_linux_reset_cause_parse("WATCHDOG"));
    TEST_ASSERT_EQUAL_INT(PMA_RESET_SOFTWARE, pma_linux_reset_cause_parse("SOFTWARE"));
    TEST_ASSERT_EQUAL_INT(PMA_RESET_PIN, pma_linux_reset_cause_parse("PIN"));
    TEST_ASSERT_EQUAL_INT(PMA_RESET_BROWNOUT, pma_linux_reset_cause_parse("BROWNOUT"));
    TEST_ASSERT_EQUAL_INT(PMA_RESET_POWER_ON, pma_linux_reset_cause_parse("POWER_ON"));
    TEST_ASSERT_EQUAL_INT(PMA_RESET_UNKNOWN, pma_linux_reset_cause_parse("watchdog"));
    TEST_ASSERT_EQUAL_INT(PMA_RESET_UNKNOWN, pma_linux_reset_cause_parse(""));
}

int main(void)
{
    UNITY_BEGIN();
    RUN_TEST(test_not_ready_and_name);
    RUN_TEST(test_no_can_devices);
    RUN_TEST(test_missing_interface);
    RUN_TEST(test_null_config_is_vcan0);
    RUN_TEST(test_config_errors);
    RUN_TEST(test_storage_errors);
    RUN_TEST(test_reinit);
    RUN_TEST(test_ring_order_and_capacity);
    RUN_TEST(test_error_frames_counters);
    RUN_TEST(test_error_frames_bus_off);
    RUN_TEST(test_reset_cause_names);
    return UNITY_END();
}
