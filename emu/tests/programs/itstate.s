@ An interrupt between the instructions of an IT block (ARMv7-M B1.5.6, A7.3.3): the
@ handler starts outside any IT block, and the rest of the interrupted block runs as
@ conditionally as it would have. The block straddles a 1 KB boundary (where the
@ emulator's translated blocks end); its first instruction pends IRQ0, which is taken
@ at that boundary, before `movne`. With Z set, `movne` is skipped: r5 stays 1. The
@ handler's first instruction sets r3 = 7 (run as part of the interrupted block it
@ would be skipped too), and the frame's xPSR holds the interrupted IT state and the
@ Thumb bit. Log: 7, the stacked xPSR, 1, then 'e'.
.include "common.inc"
.text
vectors:
    vectors_irq0 irq0

.thumb_func
.global _start
_start:
    irq0_enabled
    movs r3, #0
    movs r5, #0
    b.w near_end
.ltorg

.balign 1024
    .space 1014
near_end:
    movs r0, #0
    cmp r0, #0
    itte eq
    streq r1, [r4]
    moveq r5, #1
page:
    movne r5, #2
    LOGR r5
    LOGI 'e'
    exit_ok

.thumb_func
irq0:
    movs r3, #7
    ldr r6, [sp, #28]
    push {lr}
    LOGR r3
    LOGR r6
    pop {pc}
.ltorg
