/* SPDX-License-Identifier: Apache-2.0 */
/* Parameter storage: one opaque, versioned blob (the application's parameter
 * set, up to PMA_PSTORE_MAX_BLOB_BYTES) kept in NVM through the HAL
 * (pma_hal_nvm_*) so that a power cut at any moment of a save loses nothing.
 *
 * Two slots, A and B, each `blocks_per_slot` consecutive erase blocks (slot A
 * from first_block, slot B right after). A record, little-endian:
 *
 *   offset  size  field
 *   0       4     magic 0x50534D50 ("PMSP" in memory order)
 *   4       2     format version of this layout (PMA_PSTORE_FORMAT_VERSION)
 *   6       2     blob version (the caller's, e.g. of its parameter table)
 *   8       4     sequence number
 *   12      4     blob length n, 0..PMA_PSTORE_MAX_BLOB_BYTES
 *   16      n     blob
 *   16+n    4     CRC-32 (crc32.h) of bytes 0 .. 16+n-1
 *   then 0xFF up to the next multiple of the program size.
 *
 * A record is valid when magic, format version, length and CRC check out.
 * Save writes the slot that does NOT hold the newest valid record with
 * sequence + 1: it erases the blocks the new record covers, programs the
 * record front to back in chunks, and reads it back. The newest record is
 * never touched, so after a power cut anywhere in a save a load finds either
 * it or the complete new one (tests/storage/test_pstore_powercut.c).
 * Load takes the valid record with the newer sequence number (serial-number
 * arithmetic, RFC 1982: so the counter may wrap) and falls back to the other
 * slot when that one is invalid.
 *
 * The instance holds only the layout: every call reads the slots afresh.
 * Not for interrupt context (the HAL's NVM functions are not). */
#ifndef PMA_PSTORE_H
#define PMA_PSTORE_H

#include <stddef.h>
#include <stdint.h>

#define PMA_PSTORE_MAX_BLOB_BYTES 512u
#define PMA_PSTORE_FORMAT_VERSION 1u
#define PMA_PSTORE_MAGIC 0x50534D50u
#define PMA_PSTORE_HEADER_BYTES 16u
#define PMA_PSTORE_CRC_BYTES 4u
/* Records are written in chunks of this many bytes (a stack buffer): the NVM
 * program size must not exceed it. */
#define PMA_PSTORE_CHUNK_BYTES 32u

typedef struct pma_pstore {
    uint32_t first_block;        /* slot A: first_block .. first_block + blocks_per_slot - 1 */
    uint32_t blocks_per_slot;    /* slot B follows slot A */
    uint32_t block_size;         /* from the HAL's geometry */
    uint32_t program_size;
    uint32_t capacity;           /* largest blob that fits a slot (<= MAX_BLOB_BYTES) */
    uint8_t ready;
} pma_pstore_t;

/* What a load found. */
typedef struct pma_pstore_info {
    uint32_t len;                /* blob bytes written to the caller's buffer */
    uint16_t blob_version;       /* as given to pma_pstore_save() */
    uint32_t sequence;
    uint8_t slot;                /* 0: A, 1: B */
    uint8_t valid_slots;         /* bit 0: A valid, bit 1: B valid (one clear: a save was
                                    interrupted or a slot is corrupt) */
} pma_pstore_info_t;

/* Checks the layout against the HAL's NVM geometry (pma_hal_init() first).
 * PMA_ERR_RANGE: blocks_per_slot 0, the slots beyond the device, a slot
 * smaller than a header and CRC, or a program size above
 * PMA_PSTORE_CHUNK_BYTES. HAL errors are passed on. */
int pma_pstore_init(pma_pstore_t *ps, uint32_t first_block, uint32_t blocks_per_slot);

/* Loads the newest valid blob into blob (capacity bytes). PMA_ERR_NO_RECORD:
 * neither slot holds a valid record (use the defaults); PMA_ERR_RANGE: the
 * record is longer than capacity (nothing usable copied); a HAL error (e.g.
 * PMA_ERR_IO) when no slot is valid and a read failed. info may be NULL. */
int pma_pstore_load(const pma_pstore_t *ps, void *blob, size_t capacity,
                    pma_pstore_info_t *info);

/* Saves len bytes of blob (len 0 allowed) as the newest record. PMA_ERR_RANGE:
 * len above the capacity, nothing changed. PMA_ERR_VERIFY: the read-back
 * differed (worn flash): the new record's first block is erased again so it
 * can never load, and the previous record stays the newest.
 * A HAL error (PMA_ERR_IO: e.g. power lost) leaves the previous record the
 * newest, or, if the cut fell after the record was complete, the new one. */
int pma_pstore_save(const pma_pstore_t *ps, const void *blob, size_t len,
                    uint16_t blob_version);

#endif /* PMA_PSTORE_H */
