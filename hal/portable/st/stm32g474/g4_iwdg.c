/* SPDX-License-Identifier: Apache-2.0 */
/* Independent watchdog (RM0440 section 41), clocked by the LSI (32 kHz
 * nominal, 29.5..34 kHz: a timeout is within -8 %..+6 % of the request). */
#include "g4_drivers.h"

static uint8_t iwdg_started;

int g4_iwdg_config(uint32_t timeout_ms, g4_iwdg_regs_t *regs)
{
    if (regs == NULL) return PMA_ERR_NULL;
    if (timeout_ms == 0u || timeout_ms > G4_IWDG_MAX_MS) return PMA_ERR_RANGE;
    /* the smallest prescaler 4 << pr whose 4096 counts reach the timeout:
     * the finest resolution */
    for (uint32_t pr = 0; pr <= 6u; ++pr) {
        const uint32_t div = 4u << pr;
        const uint64_t counts =
            ((uint64_t)timeout_ms * (G4_IWDG_LSI_HZ / 1000u) + div - 1u) / div; /* rounded up */
        if (counts <= 4096u) {
            regs->pr = pr;
            regs->rlr = counts == 0u ? 0u : (uint32_t)counts - 1u; /* the counter runs RLR..0 */
            return PMA_OK;
        }
    }
    return PMA_ERR_RANGE;
}

int g4_iwdg_start(uint32_t timeout_ms)
{
    g4_iwdg_regs_t r;
    const int rc = g4_iwdg_config(timeout_ms, &r);
    if (rc != PMA_OK) return rc;
    IWDG_TypeDef *const iwdg = g4_io.iwdg;
    WRITE_REG(iwdg->KR, G4_IWDG_KEY_START); /* starts the LSI too */
    WRITE_REG(iwdg->KR, G4_IWDG_KEY_ACCESS);
    WRITE_REG(iwdg->PR, _VAL2FLD(IWDG_PR_PR, r.pr));
    WRITE_REG(iwdg->RLR, _VAL2FLD(IWDG_RLR_RL, r.rlr));
    /* the new values cross into the LSI domain: wait (bounded) until taken */
    const int ok =
        g4_wait(&iwdg->SR, IWDG_SR_PVU | IWDG_SR_RVU | IWDG_SR_WVU, 0u, G4_POLLS_LONG);
    WRITE_REG(iwdg->KR, G4_IWDG_KEY_RELOAD);
    iwdg_started = 1;
    return ok == 0 ? PMA_OK : PMA_ERR_IO;
}

void g4_iwdg_kick(void)
{
    if (iwdg_started) WRITE_REG(g4_io.iwdg->KR, G4_IWDG_KEY_RELOAD);
}
