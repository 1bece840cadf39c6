/* Reset and vector table of the C example firmware: the data copied
 * and the bss zeroed, the FPU enabled on a core that has one, then
 * main; SysTick calls systick_handler. */
#include <stdint.h>

#include "semihost.h"

extern uint32_t _sidata, _sdata, _edata, _sbss, _ebss, _stack_top;

int main(void);
void systick_handler(void);

static void halt(void)
{
    sh_exit(0);
}

void reset_handler(void)
{
    const uint32_t *src = &_sidata;
    for (uint32_t *dst = &_sdata; dst < &_edata;) *dst++ = *src++;
    for (uint32_t *dst = &_sbss; dst < &_ebss;) *dst++ = 0;
#if defined(__ARM_FP)
    /* CP10 and CP11 full access (CPACR), before any FPU instruction. */
    *(volatile uint32_t *)0xE000ED88u |= 0xFu << 20;
    __asm volatile("dsb\n isb" ::: "memory");
#endif
    sh_exit(main() == 0);
}

__attribute__((section(".vectors"), used)) static void (*const vectors[16])(void) = {
    (void (*)(void))(&_stack_top),
    reset_handler,
    halt, /* NMI */
    halt, /* HardFault */
    halt, /* MemManage */
    halt, /* BusFault */
    halt, /* UsageFault */
    0, 0, 0, 0,
    halt, /* SVCall */
    halt, /* DebugMon */
    0,
    halt, /* PendSV */
    systick_handler,
};
