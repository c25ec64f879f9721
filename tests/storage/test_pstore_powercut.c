/* SPDX-License-Identifier: Apache-2.0 */
/* The power-loss guarantee of the parameter storage: power is cut at every
 * single program and erase operation of a save, with the cut operation
 * applied to 0 %, 4 %, 25 %, 50 %, 97 % and 100 % of its bytes (a program
 * writes a prefix of its data, an erase clears a prefix of its block), and
 * once after the last operation. After power-on the load must return the
 * previous parameters or the new ones, byte for byte, never anything else,
 * and never "no record" when a valid record existed before. A save after
 * power-on must then succeed. Every sweep runs twice: on plain flash and on
 * ECC flash (a half-written unit reads as PMA_ERR_CORRUPT). Starting states: empty store, one record,
 * two records, one record plus a torn slot, and a sequence counter about to
 * wrap; old and new blobs of 0, 37 and 512 bytes. */
#include "pstore_test.h"

#include <stdio.h>

static pma_pstore_t ps;
static bool ecc; /* the sweep runs on plain flash, then on ECC flash */

static const uint32_t permilles[] = {0, 40, 250, 500, 970, 1000};
static const uint32_t sizes[] = {0, 37, PMA_PSTORE_MAX_BLOB_BYTES};

typedef enum scenario {
    EMPTY,          /* nothing saved yet */
    ONE,            /* one record (slot A) */
    TWO,            /* two records (newest in B): the save overwrites A */
    TORN,           /* one record, the other slot left torn by an earlier cut */
    WRAP,           /* the newest record has sequence 0xFFFFFFFF */
} scenario_t;

#define SEED_OLDER 1u
#define SEED_OLD 2u
#define SEED_NEW 3u
#define SEED_AFTER 4u

static struct {
    uint32_t points;        /* power cuts exercised */
    uint32_t saw_old, saw_new, saw_none;
    uint32_t corrupt_reads; /* ECC errors the loads met (and survived) */
} tally;

/* Puts the store into the scenario; returns the sequence number of the
 * newest valid record (the "old" one), or 0 when there is none. */
static uint32_t prepare(scenario_t sc, uint32_t old_len)
{
    fresh(&ps);
    pma_fake_nvm_ecc(ecc);
    switch (sc) {
    case EMPTY:
        return 0;
    case ONE:
        save_seed(&ps, SEED_OLD, old_len);
        return 1;
    case TWO:
        save_seed(&ps, SEED_OLDER, 100);
        save_seed(&ps, SEED_OLD, old_len);
        return 2;
    case TORN:
        save_seed(&ps, SEED_OLD, old_len);
        fill_blob(SEED_OLDER, 300);
        pma_fake_nvm_cut_power(8, 470); /* 5 erases, 3 programs, 15 B of the 4th */
        assert_status(pma_pstore_save(&ps, blob, 300, SEED_OLDER), PMA_ERR_IO);
        power_on(&ps);
        return 1;
    case WRAP:
    default:
        craft_record(0, 0xFFFFFFFFu, SEED_OLD, old_len);
        return 0xFFFFFFFFu;
    }
}

/* One cut: at operation `op` of the save, `permille` of it applied. */
static void cut_once(scenario_t sc, uint32_t old_len, uint32_t new_len, uint32_t ops,
                     uint32_t op, uint32_t permille)
{
    const uint32_t old_seq = prepare(sc, old_len);
    pma_fake_nvm_cut_power(op, permille);
    fill_blob(SEED_NEW, new_len);
    const int rc = pma_pstore_save(&ps, blob, new_len, SEED_NEW);
    assert_status(rc, op < ops ? PMA_ERR_IO : PMA_OK);
    power_on(&ps);
    tally.points++;

    pma_pstore_info_t info;
    memset(blob, 0xA5, sizeof blob);
    const uint32_t corrupt_before = pma_fake_nvm_corrupt_reads();
    const int lr = pma_pstore_load(&ps, blob, sizeof blob, &info);
    tally.corrupt_reads += pma_fake_nvm_corrupt_reads() - corrupt_before;
    if (lr == PMA_ERR_NO_RECORD && sc == EMPTY) {
        tally.saw_none++;
    } else {
        assert_status(lr, PMA_OK);
        const bool is_new = info.sequence == old_seq + 1u && info.len == new_len &&
                            info.blob_version == SEED_NEW && blob_is(SEED_NEW, new_len);
        const bool is_old = sc != EMPTY && info.sequence == old_seq && info.len == old_len &&
                            info.blob_version == SEED_OLD && blob_is(SEED_OLD, old_len);
        if (!is_new && !is_old) {
            pma_test_fail("scenario %d%s, old %lu B, new %lu B: cut at op %lu of %lu, "
                          "%lu permille: loaded seq %lu len %lu version %u", (int)sc,
                          ecc ? " (ECC)" : "", (unsigned long)old_len, (unsigned long)new_len,
                          (unsigned long)op, (unsigned long)ops, (unsigned long)permille,
                          (unsigned long)info.sequence, (unsigned long)info.len,
                          (unsigned)info.blob_version);
        }
        if (is_new) tally.saw_new++;
        if (is_old) tally.saw_old++;
    }
    /* the store works again: the next save succeeds and is loaded */
    fill_blob(SEED_AFTER, 33);
    assert_status(pma_pstore_save(&ps, blob, 33, SEED_AFTER), PMA_OK);
    assert_status(pma_pstore_load(&ps, blob, sizeof blob, &info), PMA_OK);
    TEST_ASSERT_TRUE(info.blob_version == SEED_AFTER && info.len == 33 && blob_is(SEED_AFTER, 33));
}

static void sweep_once(scenario_t sc)
{
    for (size_t o = 0; o < sizeof sizes / sizeof sizes[0]; ++o) {
        const uint32_t old_len = sizes[o];
        for (size_t n = 0; n < sizeof sizes / sizeof sizes[0]; ++n) {
            const uint32_t new_len = sizes[n];
            /* how many operations an uninterrupted save takes from this state */
            prepare(sc, old_len);
            const uint32_t before = pma_fake_nvm_op_count();
            fill_blob(SEED_NEW, new_len);
            assert_status(pma_pstore_save(&ps, blob, new_len, SEED_NEW), PMA_OK);
            const uint32_t ops = pma_fake_nvm_op_count() - before;
            TEST_ASSERT_GREATER_OR_EQUAL_UINT32(2, ops); /* at least one erase and one program */
            for (uint32_t op = 0; op <= ops; ++op) {
                for (size_t k = 0; k < sizeof permilles / sizeof permilles[0]; ++k) {
                    cut_once(sc, old_len, new_len, ops, op, permilles[k]);
                }
            }
        }
        if (sc == EMPTY) break; /* no old record: its size does not matter */
    }
}

static void sweep(scenario_t sc)
{
    ecc = false;
    sweep_once(sc);
    ecc = true;
    sweep_once(sc);
}

/* Every test counts its own power cuts. */
void setUp(void)
{
    memset(&tally, 0, sizeof tally);
}

static void report(const char *name)
{
    printf("%s: %lu power cuts (loaded old %lu, new %lu, none %lu; ECC errors met %lu)\n",
           name, (unsigned long)tally.points, (unsigned long)tally.saw_old,
           (unsigned long)tally.saw_new, (unsigned long)tally.saw_none,
           (unsigned long)tally.corrupt_reads);
    TEST_ASSERT_GREATER_THAN_UINT32(0, tally.saw_new);
    TEST_ASSERT_GREATER_THAN_UINT32(0, tally.corrupt_reads);
    TEST_ASSERT_TRUE(tally.saw_old > 0 || tally.saw_none > 0);
}

static void test_cut_empty_store(void)
{
    sweep(EMPTY);
    report("empty store");
}

static void test_cut_one_record(void)
{
    sweep(ONE);
    report("one record");
}

static void test_cut_two_records(void)
{
    sweep(TWO);
    report("two records");
}

static void test_cut_after_torn_save(void)
{
    sweep(TORN);
    report("torn slot");
}

static void test_cut_at_sequence_wrap(void)
{
    sweep(WRAP);
    report("sequence wrap");
}

int main(void)
{
    UNITY_BEGIN();
    RUN_TEST(test_cut_empty_store);
    RUN_TEST(test_cut_one_record);
    RUN_TEST(test_cut_two_records);
    RUN_TEST(test_cut_after_torn_save);
    RUN_TEST(test_cut_at_sequence_wrap);
    return UNITY_END();
}
