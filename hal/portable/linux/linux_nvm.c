/* SPDX-License-Identifier: Apache-2.0 */
/* Linux port: NVM in a file with flash semantics (the rules of pma/hal.h,
 * as the fake enforces them): erase sets a block to 0xFF, program writes
 * only over erased bytes, in units of PMA_HAL_LINUX_NVM_PROGRAM_SIZE. The
 * file is the raw image, block b at offset b x block_size, no header. Every
 * program and erase is synced (fdatasync) before it returns, as flash is
 * written when the operation completes. A test hook cuts the power: the
 * chosen operation reaches the file only in part, then the process ends. */
#define _GNU_SOURCE

#include "linux_internal.h"

#include "pma/hal_nvm_check.h"

#include <errno.h>
#include <fcntl.h>
#include <limits.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>

#define CHUNK_BYTES 4096u /* scratch for erased-checks and erase writes */

/* Static: one NVM device per process, used from the main loop only. */
static struct {
    int fd;                        /* -1: no storage */
    pma_nvm_geometry_t g;
    int32_t cut_after_ops;         /* -1: off */
    uint32_t cut_permille;
    uint32_t ops;                  /* program and erase operations since init */
    char path[256];                /* for messages (truncated) */
} nvm = {.fd = -1};

static uint8_t chunk[CHUNK_BYTES];

static int io_fail(const char *what)
{
    pma_linux_set_error("storage file %s: %s: %s", nvm.path, what, strerror(errno));
    return PMA_ERR_IO;
}

static int write_all(int fd, const void *data, size_t len, off_t at)
{
    const uint8_t *p = data;
    while (len > 0) {
        const ssize_t w = pwrite(fd, p, len, at);
        if (w < 0) {
            if (errno == EINTR) continue;
            return -1;
        }
        p += w;
        len -= (size_t)w;
        at += w;
    }
    return 0;
}

/* 0, or -1 with errno set (EIO for a file that ends early). */
static int read_all(int fd, void *buf, size_t len, off_t at)
{
    uint8_t *p = buf;
    while (len > 0) {
        const ssize_t r = pread(fd, p, len, at);
        if (r < 0) {
            if (errno == EINTR) continue;
            return -1;
        }
        if (r == 0) {
            errno = EIO; /* someone truncated the file */
            return -1;
        }
        p += r;
        len -= (size_t)r;
        at += r;
    }
    return 0;
}

/* Writes `len` bytes of 0xFF at `at`. */
static int write_erased(int fd, size_t len, off_t at)
{
    memset(chunk, 0xFF, sizeof chunk);
    while (len > 0) {
        const size_t n = len < sizeof chunk ? len : sizeof chunk;
        if (write_all(fd, chunk, n, at) != 0) return -1;
        len -= n;
        at += (off_t)n;
    }
    return 0;
}

/* Creates the file erased, under a temporary name renamed into place once it
 * is complete and synced: a crash while creating never leaves a file of the
 * wrong size behind (which the next start would refuse). */
static int create_erased(const char *path, uint64_t size)
{
    static char tmp[PATH_MAX + 16];
    if (snprintf(tmp, sizeof tmp, "%s.XXXXXX", path) >= (int)sizeof tmp) {
        errno = ENAMETOOLONG;
        return -1;
    }
    const int fd = mkostemp(tmp, O_CLOEXEC);
    if (fd < 0) return -1;
    if (fchmod(fd, 0644) != 0 || write_erased(fd, (size_t)size, 0) != 0 || fsync(fd) != 0 ||
        rename(tmp, path) != 0) {
        const int e = errno;
        (void)close(fd);
        (void)unlink(tmp);
        errno = e;
        return -1;
    }
    (void)close(fd);
    /* make the new directory entry durable too (best effort) */
    char *slash = strrchr(tmp, '/');
    if (slash == tmp) {
        slash[1] = '\0';
    } else if (slash != NULL) {
        *slash = '\0';
    } else {
        tmp[0] = '.';
        tmp[1] = '\0';
    }
    const int dir = open(tmp, O_RDONLY | O_DIRECTORY | O_CLOEXEC);
    if (dir >= 0) {
        (void)fsync(dir);
        (void)close(dir);
    }
    return 0;
}

int pma_linux_nvm_open(const char *path, uint32_t block_size, uint32_t block_count,
                       int32_t cut_after_ops, uint32_t cut_permille)
{
    pma_linux_nvm_close();
    (void)snprintf(nvm.path, sizeof nvm.path, "%s", path);
    const uint64_t size = (uint64_t)block_size * block_count;

    int fd = open(path, O_RDWR | O_CLOEXEC);
    if (fd < 0 && errno == ENOENT) {
        if (create_erased(path, size) != 0) return io_fail("cannot create it");
        fd = open(path, O_RDWR | O_CLOEXEC);
    }
    if (fd < 0) return io_fail("cannot open it");
    nvm.fd = fd;
    /* Two programs writing one flash image would corrupt it. */
    if (flock(fd, LOCK_EX | LOCK_NB) != 0) {
        int rc = PMA_ERR_IO;
        if (errno == EWOULDBLOCK) {
            pma_linux_set_error("storage file %s is in use by another process", nvm.path);
        } else {
            rc = io_fail("flock");
        }
        pma_linux_nvm_close();
        return rc;
    }
    struct stat st;
    if (fstat(fd, &st) != 0) {
        const int rc = io_fail("fstat");
        pma_linux_nvm_close();
        return rc;
    }
    if (!S_ISREG(st.st_mode) || (uint64_t)st.st_size != size) {
        pma_linux_set_error("storage file %s: %lld bytes, but the NVM geometry needs %llu "
                            "(%u blocks of %u bytes): delete the file, or configure the geometry "
                            "it was made with", nvm.path, (long long)st.st_size,
                            (unsigned long long)size, (unsigned)block_count, (unsigned)block_size);
        pma_linux_nvm_close();
        return PMA_ERR_RANGE;
    }
    nvm.g.block_size = block_size;
    nvm.g.block_count = block_count;
    nvm.g.program_size = PMA_HAL_LINUX_NVM_PROGRAM_SIZE;
    nvm.cut_after_ops = cut_after_ops;
    nvm.cut_permille = cut_permille;
    nvm.ops = 0;
    return PMA_OK;
}

void pma_linux_nvm_close(void)
{
    if (nvm.fd >= 0) (void)close(nvm.fd); /* also releases the lock */
    nvm.fd = -1;
}

/* Common checks of every NVM function. */
static int usable(void)
{
    if (!pma_linux_initialised()) return PMA_ERR_NOT_READY;
    if (nvm.fd < 0) return PMA_ERR_NOT_IMPLEMENTED; /* configured without storage_path */
    return PMA_OK;
}

static off_t at(uint32_t block, uint32_t offset)
{
    return (off_t)block * nvm.g.block_size + offset;
}

/* Counts one program/erase operation; returns how many of its len bytes
 * reach the file: all, or the cut prefix when the test hook picks it. */
static uint32_t operation(uint32_t len, bool *cut)
{
    *cut = nvm.cut_after_ops >= 0 && nvm.ops == (uint32_t)nvm.cut_after_ops;
    nvm.ops++;
    return *cut ? (uint32_t)((uint64_t)len * nvm.cut_permille / 1000u) : len;
}

/* After a cut operation's prefix is in the file: the power is gone. Buffered
 * stdio output is lost, as it would be. */
static void power_cut(uint32_t applied, uint32_t len)
{
    (void)fdatasync(nvm.fd);
    fprintf(stderr, "pma_hal_linux: power cut (nvm_cut_after_ops test hook): NVM operation %u "
                    "applied %u of %u bytes\n", (unsigned)nvm.ops, (unsigned)applied,
            (unsigned)len);
    _exit(PMA_HAL_LINUX_EXIT_POWER_CUT);
}

int pma_hal_nvm_geometry(pma_nvm_geometry_t *geometry)
{
    if (geometry == NULL) return PMA_ERR_NULL;
    const int rc = usable();
    if (rc != PMA_OK) return rc;
    *geometry = nvm.g;
    return PMA_OK;
}

int pma_hal_nvm_read(uint32_t block, uint32_t offset, void *buf, uint32_t len)
{
    if (buf == NULL) return PMA_ERR_NULL;
    int rc = usable();
    if (rc == PMA_OK) rc = pma_nvm_check_range(&nvm.g, block, offset, len);
    if (rc != PMA_OK) return rc;
    if (read_all(nvm.fd, buf, len, at(block, offset)) != 0) return io_fail("read");
    return PMA_OK;
}

int pma_hal_nvm_program(uint32_t block, uint32_t offset, const void *data, uint32_t len)
{
    if (data == NULL) return PMA_ERR_NULL;
    int rc = usable();
    if (rc == PMA_OK) rc = pma_nvm_check_program(&nvm.g, block, offset, len);
    if (rc != PMA_OK) return rc;
    for (uint32_t done = 0; done < len;) {
        const uint32_t n = len - done < CHUNK_BYTES ? len - done : CHUNK_BYTES;
        if (read_all(nvm.fd, chunk, n, at(block, offset + done)) != 0) return io_fail("read");
        for (uint32_t i = 0; i < n; ++i) {
            if (chunk[i] != 0xFFu) return PMA_ERR_NOT_ERASED;
        }
        done += n;
    }
    if (len == 0) return PMA_OK;
    /* Over erased bytes, flash's "program clears bits" (old & new) is just new. */
    bool cut;
    const uint32_t applied = operation(len, &cut);
    if (write_all(nvm.fd, data, applied, at(block, offset)) != 0) return io_fail("write");
    if (cut) power_cut(applied, len);
    if (fdatasync(nvm.fd) != 0) return io_fail("fdatasync");
    return PMA_OK;
}

int pma_hal_nvm_erase(uint32_t block)
{
    int rc = usable();
    if (rc == PMA_OK) rc = pma_nvm_check_range(&nvm.g, block, 0, 0);
    if (rc != PMA_OK) return rc;
    bool cut;
    const uint32_t applied = operation(nvm.g.block_size, &cut);
    if (write_erased(nvm.fd, applied, at(block, 0)) != 0) return io_fail("write");
    if (cut) power_cut(applied, nvm.g.block_size);
    if (fdatasync(nvm.fd) != 0) return io_fail("fdatasync");
    return PMA_OK;
}
