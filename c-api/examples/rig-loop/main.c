/* The rig loop in C, on the static library: one control period per
 * SysTick interrupt at 5 kHz steps the rig's bushing (rig_spec.h) on the
 * ADC code of that period. The codes are those of the Rust rig loop's
 * run of scenes/rig-loop.toml (codes.h, written by scripts/c-api.sh),
 * so the two force traces can be compared line by line.
 *
 * f32 on a core with an FPU (bushing_f32_*), Q16 without (bushing_q16_*),
 * as the Rust rig loop. After the run, thread mode prints the log in the
 * Rust rig loop's format (one "step i code force-bits" line per period)
 * and the cost of the call per period. */
#include <stdint.h>

#include "bushing.h"
#include "codes.h"
#include "rig_spec.h"
#include "semihost.h"

#if defined(__ARM_FP)
#define NUMBER "f32"
#define PART_HZ 168000000u
typedef bushing_f32_t model_t;
typedef bushing_f32_state_t state_t;
typedef bushing_f32_output_t output_t;
#else
#define NUMBER "q16"
#define PART_HZ 72000000u
typedef bushing_q16_t model_t;
typedef bushing_q16_state_t state_t;
typedef bushing_q16_output_t output_t;
#endif

/* Cycles of the reference part in one period, counted as guest
 * instructions (QEMU -icount shift=0: SysTick ticks once per 40). */
#define BUDGET (PART_HZ / 5000u)
#define PER_TICK 40u
#define PERIOD_TICKS (BUDGET / PER_TICK)

#define SYST_CSR (*(volatile uint32_t *)0xE000E010u)
#define SYST_RVR (*(volatile uint32_t *)0xE000E014u)
#define SYST_CVR (*(volatile uint32_t *)0xE000E018u)

/* The memory the library needs: the caller's. */
static model_t model;
static state_t state;
static uint32_t force_bits[RIG_PERIODS];
static volatile uint32_t period;
static uint32_t refused, errors, step_ticks_sum, step_ticks_worst;

/* Ticks since the period began (SysTick counts down). */
static uint32_t elapsed(void)
{
    return (PERIOD_TICKS - SYST_CVR) % PERIOD_TICKS;
}

/* One control period: the call a rig's interrupt makes. */
void systick_handler(void)
{
    uint32_t n = period;
    if (n >= RIG_PERIODS) return;
    uint32_t start = elapsed();
    int16_t code = rig_codes[n];
    output_t out;
#if defined(__ARM_FP)
    /* x = code * 2^-12 mm, exact. */
    bushing_status_t st = bushing_f32_step(&model, &state, (float)code * (1.0f / 4096.0f), &out);
    union { float f; uint32_t u; } bits = {out.force};
    force_bits[n] = bits.u;
#else
    /* 2^-12 mm in Q16.16 is 16 raw units. */
    bushing_status_t st = bushing_q16_step(&model, &state, (int32_t)code * 16, &out);
    force_bits[n] = (uint32_t)out.force;
#endif
    if (st == BUSHING_STATUS_REFUSED) refused++;
    else if (st != BUSHING_STATUS_OK) errors++;
    uint32_t t = elapsed() - start;
    step_ticks_sum += t;
    if (t > step_ticks_worst) step_ticks_worst = t;
    period = n + 1;
}

static void line2(const char *a, uint32_t v)
{
    char buf[96];
    char *p = fmt_str(buf, a);
    p = fmt_u32(p, v);
    fmt_str(p, "\n");
    sh_puts(buf);
}

int main(void)
{
    const bushing_spec_t spec = rig_spec();
    bushing_error_t e;
    bushing_status_t st;
#if defined(__ARM_FP)
    st = bushing_f32_init(&model, &spec, &e);
    if (st == BUSHING_STATUS_OK) st = bushing_f32_reset(&model, &state, 0.0f);
#else
    st = bushing_q16_init(&model, &spec, &e);
    if (st == BUSHING_STATUS_OK) st = bushing_q16_reset(&model, &state, 0);
#endif
    if (st != BUSHING_STATUS_OK) {
        sh_puts("error: ");
        sh_puts(bushing_status_name(st));
        sh_puts("\n");
        return 1;
    }

    SYST_RVR = PERIOD_TICKS - 1;
    SYST_CVR = 0;
    SYST_CSR = 0x7; /* core clock, interrupt, enable */
    while (period < RIG_PERIODS) __asm volatile("wfi");
    SYST_CSR = 0;

    char buf[96];
    char *p = fmt_str(buf, "rig-loop number=" NUMBER " lsb_mm=0.000244140625 rate_hz=5000 budget=");
    p = fmt_u32(p, BUDGET);
    fmt_str(p, " language=c\n");
    sh_puts(buf);
    for (uint32_t n = 0; n < RIG_PERIODS; n++) {
        p = fmt_str(buf, "step ");
        p = fmt_u32(p, n + 1);
        p = fmt_str(p, " ");
        p = fmt_i32(p, rig_codes[n]);
        p = fmt_str(p, " ");
        p = fmt_hex8(p, force_bits[n]);
        fmt_str(p, "\n");
        sh_puts(buf);
    }
    line2("periods ", period);
    line2("refused ", refused);
    line2("errors ", errors);
    line2("step_instructions_mean ", step_ticks_sum * PER_TICK / RIG_PERIODS);
    line2("step_instructions_worst ", step_ticks_worst * PER_TICK);
    line2("model_bytes ", (uint32_t)sizeof model);
    line2("state_bytes ", (uint32_t)sizeof state);
    line2("spec_bytes ", (uint32_t)sizeof spec);
    if (refused != 0 || errors != 0) return 1;
    sh_puts("verdict pass\n");
    return 0;
}
