@ Preemption and tail-chaining (ARMv7-M B1.5.4, B1.5.8; Cortex-M3 TRM 5.5).
@ IRQ0 (priority 0x80) is pended from thread mode and taken at once. It pends IRQ2
@ (0xC0, less urgent: it waits) and then IRQ1 (0x40, more urgent: it preempts at
@ once). When IRQ0 returns, IRQ2 follows by tail-chaining: on the same stack frame
@ (the SP at entry is IRQ0's), without unstacking and stacking again.
@ Log: 'A' 'a' 'B' 'b' <IRQ0 SP at entry> <IRQ2 first cycle count> <IRQ2 SP at entry>
@ 'C' 'T'; the word at LOG + 0x100 is IRQ0's last cycle count.
.include "common.inc"
.text
vectors:
    vector_table unexpected,unexpected,unexpected,unexpected,unexpected,unexpected,unexpected,unexpected,unexpected,unexpected,unexpected,unexpected,unexpected, unexpected, irq0, irq1, irq2

.thumb_func
.global _start
_start:
    dwt_on
    ldr r0, =IPR
    movs r1, #0x80
    strb r1, [r0]
    movs r1, #0x40
    strb r1, [r0, #1]
    movs r1, #0xC0
    strb r1, [r0, #2]
    ldr r0, =ISER0
    movs r1, #7
    str r1, [r0]
    ldr r0, =ISPR0
    movs r1, #1
    str r1, [r0]
    LOGI 'T'
    exit_ok

.thumb_func
irq0:
    mov r12, sp
    push {r4, r5, lr}
    LOGI 'A'
    ldr r4, =ISPR0
    movs r1, #4
    str r1, [r4]
    LOGI 'a'
    movs r1, #2
    str r1, [r4]
    LOGI 'b'
    LOGR r12
    ldr r4, =CYCCNT
    ldr r5, =LOG + 0x100
    ldr r3, [r4]
    str r3, [r5]
    pop {r4, r5, pc}

.thumb_func
irq1:
    push {lr}
    LOGI 'B'
    pop {pc}

.thumb_func
irq2:
    mov r12, sp
    ldr r1, =CYCCNT
    ldr r3, [r1]
    push {lr}
    LOGR r3
    LOGR r12
    LOGI 'C'
    pop {pc}
.ltorg
