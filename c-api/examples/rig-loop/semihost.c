#include "semihost.h"

/* One semihosting call: operation in r0, argument block in r1. */
static uint32_t sh_call(uint32_t op, const void *arg)
{
    register uint32_t r0 __asm("r0") = op;
    register const void *r1 __asm("r1") = arg;
    __asm volatile("bkpt 0xab" : "+r"(r0) : "r"(r1) : "memory");
    return r0;
}

/* The host's standard output, opened on first use (":tt" in write mode),
 * as the Rust firmware's semihosting does: SYS_WRITE0 would go to QEMU's
 * console instead. */
static int32_t out_fd = -1;

void sh_puts(const char *s)
{
    uint32_t len = 0;
    while (s[len]) len++;
    if (out_fd < 0) {
        const uint32_t open_args[3] = {(uint32_t)":tt", 4 /* "w" */, 3};
        out_fd = (int32_t)sh_call(0x01 /* SYS_OPEN */, open_args);
    }
    const uint32_t write_args[3] = {(uint32_t)out_fd, (uint32_t)s, len};
    sh_call(0x05 /* SYS_WRITE */, write_args);
}

void sh_exit(int ok)
{
    /* SYS_EXIT with ADP_Stopped_ApplicationExit (0x20026) or
     * ADP_Stopped_RunTimeErrorUnknown (0x20023): QEMU's exit status. */
    sh_call(0x18, (const void *)(ok ? 0x20026u : 0x20023u));
    for (;;) {
    }
}

char *fmt_str(char *at, const char *s)
{
    while (*s) *at++ = *s++;
    *at = 0;
    return at;
}

char *fmt_u32(char *at, uint32_t v)
{
    char digits[10];
    int n = 0;
    do {
        digits[n++] = (char)('0' + v % 10);
        v /= 10;
    } while (v);
    while (n) *at++ = digits[--n];
    *at = 0;
    return at;
}

char *fmt_i32(char *at, int32_t v)
{
    if (v < 0) {
        *at++ = '-';
        return fmt_u32(at, 0u - (uint32_t)v);
    }
    return fmt_u32(at, (uint32_t)v);
}

char *fmt_hex8(char *at, uint32_t v)
{
    for (int k = 28; k >= 0; k -= 4) *at++ = "0123456789abcdef"[(v >> k) & 0xf];
    *at = 0;
    return at;
}
