/* Semihosting for QEMU: text to the host's standard output and the exit
 * status, plus the few number formats the log needs (no libc). */
#ifndef SEMIHOST_H
#define SEMIHOST_H

#include <stdint.h>

/* Writes a NUL-terminated string. */
void sh_puts(const char *s);
/* Ends the run: QEMU exits with success when `ok`. */
void sh_exit(int ok) __attribute__((noreturn));

/* Appends to a line buffer: text, an unsigned or signed decimal, eight
 * lowercase hex digits. Each returns the new end. */
char *fmt_str(char *at, const char *s);
char *fmt_u32(char *at, uint32_t v);
char *fmt_i32(char *at, int32_t v);
char *fmt_hex8(char *at, uint32_t v);

#endif /* SEMIHOST_H */
