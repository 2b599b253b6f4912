@ Shared routines of the test programs.
.include "common.inc"
.text
.global log, unexpected

@ Append r2 to the log (r0, r1 kept).
.thumb_func
log:
    push {r0, r1}
    ldr r0, =LOG
    ldr r1, [r0]
    adds r1, #1
    str r1, [r0]
    str r2, [r0, r1, lsl #2]
    pop {r0, r1}
    bx lr

@ An exception nobody expected: log 0xDEAD and its number, exit with status 1.
.thumb_func
unexpected:
    ldr r2, =0xDEAD
    bl log
    mrs r2, ipsr
    bl log
    movs r0, #0x18
    movs r1, #1
    bkpt 0xAB
.ltorg
