/* SPDX-License-Identifier: Apache-2.0 */
/* Parameter storage in two A/B slots (record format and guarantees in pstore.h). */
#include "pstore.h"

#include <stdbool.h>
#include <string.h>

#include "crc32.h"
#include "pma/hal.h"
#include "pma/status.h"

#define OVERHEAD_BYTES (PMA_PSTORE_HEADER_BYTES + PMA_PSTORE_CRC_BYTES)
#define NO_SLOT 2u

typedef struct record_header {
    uint32_t magic;
    uint16_t format;
    uint16_t blob_version;
    uint32_t sequence;
    uint32_t len;
} record_header_t;

static void put_le16(uint8_t *p, uint16_t v)
{
    p[0] = (uint8_t)v;
    p[1] = (uint8_t)(v >> 8);
}

static void put_le32(uint8_t *p, uint32_t v)
{
    put_le16(p, (uint16_t)v);
    put_le16(p + 2, (uint16_t)(v >> 16));
}

static uint16_t get_le16(const uint8_t *p)
{
    return (uint16_t)(p[0] | (uint16_t)p[1] << 8);
}

static uint32_t get_le32(const uint8_t *p)
{
    return get_le16(p) | (uint32_t)get_le16(p + 2) << 16;
}

static void header_encode(const record_header_t *h, uint8_t out[PMA_PSTORE_HEADER_BYTES])
{
    put_le32(out + 0, h->magic);
    put_le16(out + 4, h->format);
    put_le16(out + 6, h->blob_version);
    put_le32(out + 8, h->sequence);
    put_le32(out + 12, h->len);
}

static void header_decode(const uint8_t in[PMA_PSTORE_HEADER_BYTES], record_header_t *h)
{
    h->magic = get_le32(in + 0);
    h->format = get_le16(in + 4);
    h->blob_version = get_le16(in + 6);
    h->sequence = get_le32(in + 8);
    h->len = get_le32(in + 12);
}

static uint32_t min_u32(uint32_t a, uint32_t b)
{
    return a < b ? a : b;
}

static uint32_t slot_block(const pma_pstore_t *ps, uint32_t slot)
{
    return ps->first_block + slot * ps->blocks_per_slot;
}

/* a follows b in serial-number arithmetic (RFC 1982): the counter may wrap;
 * exactly half-way apart is undefined and counts as "not newer" both ways. */
static bool seq_newer(uint32_t a, uint32_t b)
{
    const uint32_t d = a - b;
    return d != 0 && d < 0x80000000u;
}

/* Reads len bytes from byte position pos of a slot, across blocks. Data the
 * device flags as corrupt (flash ECC, e.g. a unit torn by a power cut) makes
 * the slot invalid, like a CRC mismatch: PMA_ERR_NO_RECORD. */
static int slot_read(const pma_pstore_t *ps, uint32_t slot, uint32_t pos, void *buf,
                     uint32_t len)
{
    uint8_t *p = buf;
    while (len > 0) {
        const uint32_t off = pos % ps->block_size;
        const uint32_t n = min_u32(len, ps->block_size - off);
        const int rc = pma_hal_nvm_read(slot_block(ps, slot) + pos / ps->block_size, off, p, n);
        if (rc == PMA_ERR_CORRUPT) return PMA_ERR_NO_RECORD;
        if (rc != PMA_OK) return rc;
        pos += n;
        p += n;
        len -= n;
    }
    return PMA_OK;
}

/* PMA_OK with the header when the slot holds a valid record; PMA_ERR_NO_RECORD
 * when it does not; a HAL error when a read failed. The payload is streamed
 * through a small buffer, so no blob-sized memory is needed. */
static int slot_check(const pma_pstore_t *ps, uint32_t slot, record_header_t *h)
{
    uint8_t buf[PMA_PSTORE_CHUNK_BYTES];
    int rc = slot_read(ps, slot, 0, buf, PMA_PSTORE_HEADER_BYTES);
    if (rc != PMA_OK) return rc;
    header_decode(buf, h);
    if (h->magic != PMA_PSTORE_MAGIC || h->format != PMA_PSTORE_FORMAT_VERSION ||
        h->len > ps->capacity) {
        return PMA_ERR_NO_RECORD;
    }
    uint32_t crc = pma_crc32_update(0u, buf, PMA_PSTORE_HEADER_BYTES);
    uint32_t pos = PMA_PSTORE_HEADER_BYTES;
    for (uint32_t left = h->len; left > 0;) {
        const uint32_t n = min_u32(left, sizeof buf);
        rc = slot_read(ps, slot, pos, buf, n);
        if (rc != PMA_OK) return rc;
        crc = pma_crc32_update(crc, buf, n);
        pos += n;
        left -= n;
    }
    rc = slot_read(ps, slot, pos, buf, PMA_PSTORE_CRC_BYTES);
    if (rc != PMA_OK) return rc;
    return get_le32(buf) == crc ? PMA_OK : PMA_ERR_NO_RECORD;
}

/* Both slots: rc[] and h[] per slot; returns the slot holding the newest
 * valid record (A on a tie) or NO_SLOT. */
static uint32_t scan(const pma_pstore_t *ps, int rc[2], record_header_t h[2])
{
    for (uint32_t s = 0; s < 2; ++s) rc[s] = slot_check(ps, s, &h[s]);
    if (rc[0] == PMA_OK && rc[1] == PMA_OK) {
        return seq_newer(h[1].sequence, h[0].sequence) ? 1u : 0u;
    }
    if (rc[0] == PMA_OK) return 0;
    if (rc[1] == PMA_OK) return 1;
    return NO_SLOT;
}

/* The error to report when no slot is usable: a read failure wins over "no record". */
static int no_record(const int rc[2])
{
    for (uint32_t s = 0; s < 2; ++s) {
        if (rc[s] != PMA_OK && rc[s] != PMA_ERR_NO_RECORD) return rc[s];
    }
    return PMA_ERR_NO_RECORD;
}

int pma_pstore_init(pma_pstore_t *ps, uint32_t first_block, uint32_t blocks_per_slot)
{
    if (ps == NULL) return PMA_ERR_NULL;
    ps->ready = 0;
    pma_nvm_geometry_t g;
    const int rc = pma_hal_nvm_geometry(&g);
    if (rc != PMA_OK) return rc;
    if (g.program_size == 0 || g.program_size > PMA_PSTORE_CHUNK_BYTES) return PMA_ERR_RANGE;
    if (g.block_size == 0 || g.block_size % g.program_size != 0) return PMA_ERR_RANGE;
    if (blocks_per_slot == 0 || first_block > g.block_count ||
        blocks_per_slot > (g.block_count - first_block) / 2u) {
        return PMA_ERR_RANGE;
    }
    if (blocks_per_slot > UINT32_MAX / g.block_size) return PMA_ERR_RANGE;
    const uint32_t slot_bytes = blocks_per_slot * g.block_size;
    if (slot_bytes < OVERHEAD_BYTES) return PMA_ERR_RANGE;
    ps->first_block = first_block;
    ps->blocks_per_slot = blocks_per_slot;
    ps->block_size = g.block_size;
    ps->program_size = g.program_size;
    /* the padded record fits: slot_bytes is a multiple of the program size */
    ps->capacity = min_u32(PMA_PSTORE_MAX_BLOB_BYTES, slot_bytes - OVERHEAD_BYTES);
    ps->ready = 1;
    return PMA_OK;
}

int pma_pstore_load(const pma_pstore_t *ps, void *blob, size_t capacity,
                    pma_pstore_info_t *info)
{
    if (ps == NULL || blob == NULL) return PMA_ERR_NULL;
    if (!ps->ready) return PMA_ERR_NOT_READY;
    int rc[2];
    record_header_t h[2];
    const uint32_t newest = scan(ps, rc, h);
    if (newest == NO_SLOT) return no_record(rc);
    for (uint32_t k = 0; k < 2; ++k) {
        const uint32_t s = k == 0 ? newest : 1u - newest; /* fall back to the other slot */
        if (rc[s] != PMA_OK) continue;
        if (h[s].len > capacity) return PMA_ERR_RANGE;
        /* copy and check again: what reaches the caller is what the CRC covered */
        uint8_t buf[PMA_PSTORE_HEADER_BYTES];
        header_encode(&h[s], buf);
        uint32_t crc = pma_crc32_update(0u, buf, PMA_PSTORE_HEADER_BYTES);
        int r = slot_read(ps, s, PMA_PSTORE_HEADER_BYTES, blob, h[s].len);
        if (r == PMA_OK) {
            r = slot_read(ps, s, PMA_PSTORE_HEADER_BYTES + h[s].len, buf, PMA_PSTORE_CRC_BYTES);
        }
        if (r != PMA_OK || get_le32(buf) != pma_crc32_update(crc, blob, h[s].len)) {
            rc[s] = r != PMA_OK ? r : PMA_ERR_NO_RECORD;
            continue;
        }
        if (info != NULL) {
            info->len = h[s].len;
            info->blob_version = h[s].blob_version;
            info->sequence = h[s].sequence;
            info->slot = (uint8_t)s;
            info->valid_slots = (uint8_t)((rc[0] == PMA_OK ? 1u : 0u) | (rc[1] == PMA_OK ? 2u : 0u));
        }
        return PMA_OK;
    }
    return no_record(rc);
}

/* Streams a record into a slot through a chunk buffer; each flush is one
 * program operation of a multiple of the program size within one block. */
typedef struct writer {
    const pma_pstore_t *ps;
    uint32_t slot;
    uint32_t pos;                /* slot byte position of buf[0], program-aligned */
    uint32_t fill;
    uint8_t buf[PMA_PSTORE_CHUNK_BYTES];
} writer_t;

static uint32_t writer_room(const writer_t *w)
{
    const uint32_t chunk = PMA_PSTORE_CHUNK_BYTES - PMA_PSTORE_CHUNK_BYTES % w->ps->program_size;
    return min_u32(chunk, w->ps->block_size - w->pos % w->ps->block_size);
}

static int writer_flush(writer_t *w)
{
    if (w->fill == 0) return PMA_OK;
    const uint32_t ps = w->ps->program_size;
    const uint32_t padded = (w->fill + ps - 1u) / ps * ps;
    memset(w->buf + w->fill, 0xFF, padded - w->fill);
    const int rc = pma_hal_nvm_program(slot_block(w->ps, w->slot) + w->pos / w->ps->block_size,
                                       w->pos % w->ps->block_size, w->buf, padded);
    w->pos += padded;
    w->fill = 0;
    return rc;
}

static int writer_put(writer_t *w, const void *data, uint32_t len)
{
    const uint8_t *p = data;
    while (len > 0) {
        const uint32_t n = min_u32(len, writer_room(w) - w->fill);
        memcpy(w->buf + w->fill, p, n);
        w->fill += n;
        p += n;
        len -= n;
        if (w->fill == writer_room(w)) {
            const int rc = writer_flush(w);
            if (rc != PMA_OK) return rc;
        }
    }
    return PMA_OK;
}

static int write_record(const pma_pstore_t *ps, uint32_t slot, const record_header_t *h,
                        const void *blob)
{
    /* erase only the blocks the record covers: bytes beyond its length are never read */
    const uint32_t bytes = PMA_PSTORE_HEADER_BYTES + h->len + PMA_PSTORE_CRC_BYTES;
    const uint32_t blocks = (bytes + ps->block_size - 1u) / ps->block_size;
    for (uint32_t b = 0; b < blocks; ++b) {
        const int rc = pma_hal_nvm_erase(slot_block(ps, slot) + b);
        if (rc != PMA_OK) return rc;
    }
    uint8_t hdr[PMA_PSTORE_HEADER_BYTES];
    header_encode(h, hdr);
    uint8_t crc[PMA_PSTORE_CRC_BYTES];
    put_le32(crc, pma_crc32_update(pma_crc32_update(0u, hdr, sizeof hdr), blob, h->len));
    writer_t w = {.ps = ps, .slot = slot};
    int rc = writer_put(&w, hdr, sizeof hdr);
    if (rc == PMA_OK && h->len > 0) rc = writer_put(&w, blob, h->len);
    if (rc == PMA_OK) rc = writer_put(&w, crc, sizeof crc);
    if (rc == PMA_OK) rc = writer_flush(&w);
    return rc;
}

/* The slot holds exactly the record h with payload blob. */
static int verify(const pma_pstore_t *ps, uint32_t slot, const record_header_t *h,
                  const void *blob)
{
    record_header_t got;
    int rc = slot_check(ps, slot, &got);
    if (rc == PMA_ERR_NO_RECORD) return PMA_ERR_VERIFY;
    if (rc != PMA_OK) return rc;
    if (got.sequence != h->sequence || got.len != h->len || got.blob_version != h->blob_version) {
        return PMA_ERR_VERIFY;
    }
    const uint8_t *p = blob;
    uint8_t buf[PMA_PSTORE_CHUNK_BYTES];
    for (uint32_t pos = 0; pos < h->len;) {
        const uint32_t n = min_u32(h->len - pos, sizeof buf);
        rc = slot_read(ps, slot, PMA_PSTORE_HEADER_BYTES + pos, buf, n);
        if (rc == PMA_ERR_NO_RECORD) return PMA_ERR_VERIFY;
        if (rc != PMA_OK) return rc;
        if (memcmp(buf, p + pos, n) != 0) return PMA_ERR_VERIFY;
        pos += n;
    }
    return PMA_OK;
}

int pma_pstore_save(const pma_pstore_t *ps, const void *blob, size_t len,
                    uint16_t blob_version)
{
    if (ps == NULL || (blob == NULL && len > 0)) return PMA_ERR_NULL;
    if (!ps->ready) return PMA_ERR_NOT_READY;
    if (len > ps->capacity) return PMA_ERR_RANGE;
    int rc[2];
    record_header_t h[2];
    const uint32_t newest = scan(ps, rc, h);
    /* a failing device: change nothing (a missing record is no failure) */
    for (uint32_t s = 0; s < 2; ++s) {
        if (rc[s] != PMA_OK && rc[s] != PMA_ERR_NO_RECORD) return rc[s];
    }
    const uint32_t target = newest == 0 ? 1u : 0u; /* never the newest */
    const record_header_t rec = {
        .magic = PMA_PSTORE_MAGIC,
        .format = PMA_PSTORE_FORMAT_VERSION,
        .blob_version = blob_version,
        .sequence = newest == NO_SLOT ? 1u : h[newest].sequence + 1u,
        .len = (uint32_t)len,
    };
    int r = write_record(ps, target, &rec, blob);
    if (r != PMA_OK) return r;
    r = verify(ps, target, &rec, blob);
    if (r == PMA_ERR_VERIFY) {
        /* never leave a record that differs from what was asked for */
        (void)pma_hal_nvm_erase(slot_block(ps, target));
    }
    return r;
}
