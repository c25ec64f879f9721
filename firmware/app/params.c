/* SPDX-License-Identifier: Apache-2.0 */
/* Parameter access by id: see params.h. */
#include "params.h"
#include "pma/finite.h"

#include <math.h>
#include <string.h>

const pma_param_desc_t *pma_param_find(uint16_t id)
{
    /* binary search: the generated table is sorted by id */
    size_t lo = 0, hi = PMA_PARAM_COUNT;
    while (lo < hi) {
        size_t mid = lo + (hi - lo) / 2u;
        if (pma_param_table[mid].id == id) return &pma_param_table[mid];
        if (pma_param_table[mid].id < id) {
            lo = mid + 1u;
        } else {
            hi = mid;
        }
    }
    return NULL;
}

static void *field(pma_params_t *p, const pma_param_desc_t *d)
{
    return (uint8_t *)p + d->offset;
}

static const void *cfield(const pma_params_t *p, const pma_param_desc_t *d)
{
    return (const uint8_t *)p + d->offset;
}

void pma_params_defaults(pma_params_t *p)
{
    if (p == NULL) return;
    memset(p, 0, sizeof *p);
    for (size_t i = 0; i < PMA_PARAM_COUNT; ++i) {
        memcpy(field(p, &pma_param_table[i]), &pma_param_table[i].def, 4u);
    }
}

int pma_param_get(const pma_params_t *p, uint16_t id, pma_param_type_t *type,
                  pma_param_value_t *value)
{
    if (p == NULL || type == NULL || value == NULL) return PMA_ERR_NULL;
    const pma_param_desc_t *d = pma_param_find(id);
    if (d == NULL) return PMA_ERR_UNKNOWN_ID;
    *type = (pma_param_type_t)d->type;
    memcpy(value, cfield(p, d), 4u);
    return PMA_OK;
}

static int check_range(const pma_param_desc_t *d, pma_param_value_t v)
{
    switch (d->type) {
    case PMA_PARAM_F32:
        if (!pma_isfinite_f32(v.f32)) return PMA_ERR_NOT_FINITE;
        return (v.f32 >= d->min.f32 && v.f32 <= d->max.f32) ? PMA_OK : PMA_ERR_RANGE;
    case PMA_PARAM_U32:
        return (v.u32 >= d->min.u32 && v.u32 <= d->max.u32) ? PMA_OK : PMA_ERR_RANGE;
    default:
        return (v.i32 >= d->min.i32 && v.i32 <= d->max.i32) ? PMA_OK : PMA_ERR_RANGE;
    }
}

int pma_param_check(uint16_t id, pma_param_type_t type, pma_param_value_t value,
                    pma_param_phase_t phase)
{
    const pma_param_desc_t *d = pma_param_find(id);
    if (d == NULL) return PMA_ERR_UNKNOWN_ID;
    if ((unsigned)type != d->type) return PMA_ERR_TYPE;
    int rc = check_range(d, value);
    if (rc != PMA_OK) return rc;
    switch (d->access) {
    case PMA_PARAM_LIVE: return PMA_OK;
    case PMA_PARAM_STOPPED: return phase == PMA_PHASE_RUNNING ? PMA_ERR_STATE : PMA_OK;
    default: return phase == PMA_PHASE_INACTIVE ? PMA_OK : PMA_ERR_STATE;
    }
}

int pma_param_set(pma_params_t *p, uint16_t id, pma_param_type_t type,
                  pma_param_value_t value, pma_param_phase_t phase)
{
    if (p == NULL) return PMA_ERR_NULL;
    int rc = pma_param_check(id, type, value, phase);
    if (rc != PMA_OK) return rc;
    memcpy(field(p, pma_param_find(id)), &value, 4u);
    return PMA_OK;
}

int pma_param_next_id(uint16_t after, uint16_t *next_id)
{
    if (next_id == NULL) return PMA_ERR_NULL;
    for (size_t i = 0; i < PMA_PARAM_COUNT; ++i) {
        if (pma_param_table[i].id > after) {
            *next_id = pma_param_table[i].id;
            return PMA_OK;
        }
    }
    return PMA_ERR_EMPTY;
}

size_t pma_params_serialize(const pma_params_t *p, uint8_t *buf, size_t capacity)
{
    if (p == NULL || buf == NULL || capacity < PMA_PARAMS_BLOB_BYTES) return 0;
    for (size_t i = 0; i < PMA_PARAM_COUNT; ++i) {
        const pma_param_desc_t *d = &pma_param_table[i];
        uint32_t raw;
        memcpy(&raw, cfield(p, d), 4u);
        uint8_t *e = buf + i * PMA_PARAMS_ENTRY_BYTES;
        e[0] = (uint8_t)d->id;
        e[1] = (uint8_t)(d->id >> 8);
        for (unsigned b = 0; b < 4u; ++b) e[2u + b] = (uint8_t)(raw >> (8u * b));
    }
    return PMA_PARAMS_BLOB_BYTES;
}

int pma_params_deserialize(pma_params_t *p, const uint8_t *buf, size_t len)
{
    if (p == NULL || (buf == NULL && len != 0)) return PMA_ERR_NULL;
    pma_params_defaults(p);
    if (len % PMA_PARAMS_ENTRY_BYTES != 0) return PMA_ERR_RANGE;
    int rejected = 0;
    for (size_t off = 0; off < len; off += PMA_PARAMS_ENTRY_BYTES) {
        const uint8_t *e = buf + off;
        uint16_t id = (uint16_t)(e[0] | (e[1] << 8));
        uint32_t raw = (uint32_t)e[2] | ((uint32_t)e[3] << 8) | ((uint32_t)e[4] << 16) |
                       ((uint32_t)e[5] << 24);
        const pma_param_desc_t *d = pma_param_find(id);
        if (d == NULL) continue; /* a parameter this firmware no longer has */
        pma_param_value_t v;
        v.u32 = raw;
        if (pma_param_set(p, id, (pma_param_type_t)d->type, v, PMA_PHASE_INACTIVE) != PMA_OK) {
            ++rejected;
        }
    }
    return rejected;
}
