@ BASEPRI and PRIMASK (ARMv7-M B1.5.4: execution priority). With BASEPRI = 0x80, IRQ0
@ (priority 0x80) stays pending and IRQ1 (0x40) is taken; writing BASEPRI = 0 takes
@ IRQ0 before the next log. With PRIMASK set nothing is taken; cpsie takes IRQ1.
@ Log: 'm' 'B' 'n' 'A' 'u' 'p' 'B' 'q'.
.include "common.inc"
.text
vectors:
    vector_table unexpected,unexpected,unexpected,unexpected,unexpected,unexpected,unexpected,unexpected,unexpected,unexpected,unexpected,unexpected,unexpected, unexpected, irq0, irq1

.thumb_func
.global _start
_start:
    ldr r0, =IPR
    movs r1, #0x80
    strb r1, [r0]
    movs r1, #0x40
    strb r1, [r0, #1]
    ldr r0, =ISER0
    movs r1, #3
    str r1, [r0]
    movs r0, #0x80
    msr basepri, r0
    ldr r4, =ISPR0
    movs r1, #1
    str r1, [r4]
    LOGI 'm'
    movs r1, #2
    str r1, [r4]
    LOGI 'n'
    movs r0, #0
    msr basepri, r0
    LOGI 'u'
    cpsid i
    movs r1, #2
    str r1, [r4]
    LOGI 'p'
    cpsie i
    LOGI 'q'
    exit_ok

.thumb_func
irq0:
    push {lr}
    LOGI 'A'
    pop {pc}

.thumb_func
irq1:
    push {lr}
    LOGI 'B'
    pop {pc}
.ltorg
