/* SPDX-License-Identifier: Apache-2.0 */
/* The node's identity on the wire: DEVICE_INFO, five pages sent at once in reply to
 * DEVICE_INFO_REQ (this node) and DEVICE_INFO_REQ_ALL (every node; how a scan finds two devices
 * on one node id). What it reports comes from one place each: the protocol version from the
 * DBC's VERSION line (generated/pma_proto_version.h), the firmware version, commit and target
 * from the build (build_info.h), the parameter table's size and hash from params.toml
 * (generated/pma_param_table.h), the unique id from the platform (pma_app_platform_t). */
#include <string.h>

#include "app_core.h"
#include "app_frames.h"
#include "build_info.h"
#include "generated/pma_proto.h"
#include "generated/pma_proto_version.h"

enum { PAGE_VERSION, PAGE_COMMIT, PAGE_PARAMS, PAGE_UID_LOW, PAGE_UID_HIGH, PAGE_COUNT };

_Static_assert(PAGE_VERSION == PMA_PROTO_DEVICE_INFO_PAGE_VERSION_CHOICE &&
                   PAGE_COMMIT == PMA_PROTO_DEVICE_INFO_PAGE_COMMIT_CHOICE &&
                   PAGE_PARAMS == PMA_PROTO_DEVICE_INFO_PAGE_PARAMS_CHOICE &&
                   PAGE_UID_LOW == PMA_PROTO_DEVICE_INFO_PAGE_UID_LOW_CHOICE &&
                   PAGE_UID_HIGH == PMA_PROTO_DEVICE_INFO_PAGE_UID_HIGH_CHOICE,
               "DEVICE_INFO pages: the DBC's VAL_ table");
_Static_assert(PMA_PARAM_COUNT <= 255u, "ParamCount is 8 bits");
_Static_assert(PMA_PROTO_VERSION <= 255u, "ProtocolVersion is 8 bits");

/* Bytes [first, first + n) of the unique id as a little-endian number (byte first lowest). */
static uint64_t uid_bits(const pma_app_t *app, unsigned first, unsigned n)
{
    uint64_t v = 0;
    for (unsigned k = n; k-- > 0;) v = (v << 8) | app->plat.device_uid[first + k];
    return v;
}

/* DeviceTag: CRC-8, polynomial 0x07 (x^8 + x^2 + x + 1), initial value 0, no reflection, of the
 * unique id; in every page, so that interleaved pages of two devices on one node id part. */
static uint8_t device_tag(const uint8_t *uid)
{
    uint8_t crc = 0;
    for (unsigned k = 0; k < PMA_DEVICE_UID_BYTES; ++k) {
        crc ^= uid[k];
        for (unsigned b = 0; b < 8u; ++b) {
            const unsigned shifted = (unsigned)crc << 1;
            crc = (uint8_t)((crc & 0x80u) ? shifted ^ 0x07u : shifted);
        }
    }
    return crc;
}

void pma_app_send_device_info(pma_app_t *app)
{
    const uint8_t tag = device_tag(app->plat.device_uid);
    for (uint8_t page = 0; page < PAGE_COUNT; ++page) {
        struct pma_proto_device_info_t m;
        memset(&m, 0, sizeof m);
        m.page = page;
        m.device_tag = tag;
        switch (page) {
        case PAGE_VERSION:
            m.protocol_version = (uint8_t)PMA_PROTO_VERSION;
            m.fw_major = pma_build_info.fw_major;
            m.fw_minor = pma_build_info.fw_minor;
            m.fw_patch = pma_build_info.fw_patch;
            m.build_target = pma_build_info.build_target;
            m.build_flags = pma_build_info.build_flags;
            break;
        case PAGE_COMMIT:
            m.fw_commit = pma_build_info.fw_commit;
            m.param_count = (uint8_t)PMA_PARAM_COUNT;
            break;
        case PAGE_PARAMS:
            m.param_table_hash = PMA_PARAM_TABLE_HASH;
            break;
        case PAGE_UID_LOW:
            m.uid_low = uid_bits(app, 0u, 6u);
            break;
        default:
            m.uid_high = uid_bits(app, 6u, 6u);
            break;
        }
        uint8_t d[8] = {0};
        (void)pma_proto_device_info_pack(d, &m, sizeof d);
        (void)pma_app_send_frame(app, PMA_PROTO_DEVICE_INFO_FRAME_ID, PMA_PROTO_DEVICE_INFO_LENGTH, d);
    }
}
