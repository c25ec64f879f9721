/* SPDX-License-Identifier: Apache-2.0 */
/* Parameters: the table (generated from params.toml), typed access by id with
 * range, type, NaN and state checks, defaults, and the storage format.
 *
 * Values live in a pma_params_t (generated/pma_param_table.h); every access by
 * id goes through pma_param_get() / pma_param_set(), which never change
 * anything when they return an error. No global state: the caller owns the
 * pma_params_t. */
#ifndef PMA_PARAMS_H
#define PMA_PARAMS_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "generated/pma_param_table.h"
#include "pma/status.h"

typedef enum pma_param_type {
    PMA_PARAM_F32 = 0,  /* same numbers as the PARAM_REQ Type signal */
    PMA_PARAM_U32 = 1,
    PMA_PARAM_I32 = 2,
} pma_param_type_t;

/* When a SET is allowed (docs/parameters.md). */
typedef enum pma_param_access {
    PMA_PARAM_LIVE = 0,     /* any state */
    PMA_PARAM_STOPPED = 1,  /* not while RUNNING */
    PMA_PARAM_IDLE = 2,     /* only while the output is inactive */
} pma_param_access_t;

/* One value, raw 32 bits, interpreted by the parameter's type. */
typedef union pma_param_value {
    float f32;
    uint32_t u32;
    int32_t i32;
} pma_param_value_t;

typedef struct pma_param_desc {
    uint16_t id;
    const char *name;
    uint8_t type;       /* pma_param_type_t */
    uint8_t access;     /* pma_param_access_t */
    uint16_t offset;    /* of the field in pma_params_t */
    pma_param_value_t min, max, def;
} pma_param_desc_t;

/* The table, sorted by id (generated/pma_param_table.c). */
extern const pma_param_desc_t pma_param_table[PMA_PARAM_COUNT];

/* What the caller's state allows (the application maps its state machine). */
typedef enum pma_param_phase {
    PMA_PHASE_INACTIVE = 0, /* output inactive: every access class may be set */
    PMA_PHASE_ARMED = 1,    /* output active, not running: live and stopped */
    PMA_PHASE_RUNNING = 2,  /* live only */
} pma_param_phase_t;

/* The descriptor of id, or NULL. */
const pma_param_desc_t *pma_param_find(uint16_t id);

/* Sets every parameter to its default. */
void pma_params_defaults(pma_params_t *p);

/* The current value of id. PMA_ERR_UNKNOWN_ID or PMA_ERR_NULL. */
int pma_param_get(const pma_params_t *p, uint16_t id, pma_param_type_t *type,
                  pma_param_value_t *value);

/* Checks a value for id without setting it: PMA_ERR_UNKNOWN_ID, PMA_ERR_TYPE
 * (type is not the parameter's), PMA_ERR_NOT_FINITE (NaN, infinity),
 * PMA_ERR_RANGE (outside min..max), PMA_ERR_STATE (phase forbids it). */
int pma_param_check(uint16_t id, pma_param_type_t type, pma_param_value_t value,
                    pma_param_phase_t phase);

/* pma_param_check(), then stores the value. Nothing changes on error. */
int pma_param_set(pma_params_t *p, uint16_t id, pma_param_type_t type,
                  pma_param_value_t value, pma_param_phase_t phase);

/* Index of the first parameter with an id above `after` (0: the first), as
 * its id in *next_id. PMA_ERR_EMPTY after the last. */
int pma_param_next_id(uint16_t after, uint16_t *next_id);

/* Storage format (the blob of one pstore record, version
 * PMA_PARAMS_BLOB_VERSION): PMA_PARAM_COUNT entries of 6 bytes, little-endian
 * id (2 bytes) and raw value (4 bytes). Loading by id keeps a stored set
 * usable across firmware versions: unknown ids are skipped, parameters
 * missing from the blob keep their defaults, a stored value that fails
 * pma_param_check() (its range changed) is replaced by the default. */
#define PMA_PARAMS_BLOB_VERSION 1u
#define PMA_PARAMS_ENTRY_BYTES 6u
#define PMA_PARAMS_BLOB_BYTES (PMA_PARAM_COUNT * PMA_PARAMS_ENTRY_BYTES)

/* Writes the blob of p into buf (PMA_PARAMS_BLOB_BYTES); returns its length. */
size_t pma_params_serialize(const pma_params_t *p, uint8_t *buf, size_t capacity);

/* Rebuilds p from defaults plus a blob; returns how many stored values were
 * rejected (replaced by defaults), or PMA_ERR_RANGE for a length that is not
 * a whole number of entries (p then holds the defaults). */
int pma_params_deserialize(pma_params_t *p, const uint8_t *buf, size_t len);

#endif /* PMA_PARAMS_H */
