@ Exception entry with the stack at 4 mod 8 (ARMv7-M B1.5.6, B1.5.7): with
@ CCR.STKALIGN clear (the Cortex-M3 r1p1's reset value) the frame goes right below
@ the SP, so the handler's SP is 4 mod 8; with it set, a word of padding aligns the
@ frame to 8 bytes and the stacked xPSR's bit 9 says so; the return takes the padding
@ back. Log per entry: the handler's SP, the stacked xPSR's bit 9; then the thread's
@ SP after the returns.
.include "common.inc"
.equ CCR, 0xE000ED14
.text
vectors:
    vectors_irq0 irq0

.thumb_func
.global _start
_start:
    irq0_enabled
    sub sp, #4
    str r1, [r4]
    dsb
    isb
    ldr r0, =CCR
    ldr r1, [r0]
    orr r1, r1, #0x200
    str r1, [r0]
    movs r1, #1
    str r1, [r4]
    dsb
    isb
    LOGR sp
    exit_ok

.thumb_func
irq0:
    mov r2, sp
    bl log
    ldr r2, [sp, #28]
    ubfx r2, r2, #9, #1
    bl log
    ldr r0, =0xFFFFFFF9
    bx r0
.ltorg
