/* SPDX-License-Identifier: Apache-2.0 */
/* CRC-32 as in IEEE 802.3, zlib and PNG ("CRC-32/ISO-HDLC"): polynomial
 * 0x04C11DB7 processed bit-reflected (0xEDB88320), initial value 0xFFFFFFFF,
 * final XOR 0xFFFFFFFF. Check value: CRC of the ASCII "123456789" is
 * 0xCBF43926. A 16-entry table (64 bytes of flash), two steps per byte. */
#ifndef PMA_CRC32_H
#define PMA_CRC32_H

#include <stddef.h>
#include <stdint.h>

#define PMA_CRC32_CHECK 0xCBF43926u

/* CRC of data appended to data whose CRC is `crc` (0 for nothing): chains,
 * so update(update(0, a), b) equals the CRC of a followed by b. */
uint32_t pma_crc32_update(uint32_t crc, const void *data, size_t len);

static inline uint32_t pma_crc32(const void *data, size_t len)
{
    return pma_crc32_update(0u, data, len);
}

#endif /* PMA_CRC32_H */
