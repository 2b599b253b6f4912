@ The independent watchdog (RM0008 19.3): started with prescaler /4 and reload 100,
@ it counts 101 x 4 periods of the 40 kHz LSI (10.1 ms) from its last reload and then
@ resets the MCU; RCC_CSR shows IWDGRSTF after that reset (7.3.10).
@ First boot (no IWDGRSTF): log RCC_CSR, start the watchdog, reload it five times
@ about 5 ms apart (a delay loop), log the cycle count at the last reload, then stop
@ reloading. After the reset: log RCC_CSR again and exit.
.include "common.inc"
.equ IWDG_KR, 0x40003000
.equ RCC_CSR, 0x40021024
.text
vectors:
    vector_table unexpected,unexpected,unexpected,unexpected,unexpected,unexpected,unexpected,unexpected,unexpected,unexpected,unexpected,unexpected,unexpected, unexpected

.thumb_func
.global _start
_start:
    ldr r0, =RCC_CSR
    ldr r4, [r0]
    LOGR r4
    tst r4, #0x20000000
    bne after_reset
    dwt_on
    ldr r5, =IWDG_KR
    movw r1, #0x5555
    str r1, [r5]
    movs r1, #0
    str r1, [r5, #4]
    movs r1, #100
    str r1, [r5, #8]
    movw r1, #0xCCCC
    str r1, [r5]
    movw r6, #0xAAAA
    movs r7, #5
feed:
    movw r0, #13333
delay:
    subs r0, #1
    bne delay
    str r6, [r5]
    subs r7, #1
    bne feed
    ldr r0, =CYCCNT
    ldr r0, [r0]
    LOGR r0
forever:
    b forever
after_reset:
    exit_ok
.ltorg
