@ Late arrival (ARMv7-M B1.5.4, Cortex-M3 TRM 5.5.2): SysTick (priority 0x80) and
@ TIM2's update (IRQ28, 0x40) are due D - 0.5 cycles apart, D read from 0x20001000.
@ When TIM2's comes while SysTick's frame is being stacked, TIM2's handler runs first
@ on that frame and SysTick's follows by tail-chaining (both see the same SP at
@ entry); when it comes later, it preempts SysTick's handler (a second frame).
@ TIM2 counts ARR + 1 = 1001 + D ticks of the 8 MHz clock from its start; SysTick,
@ started one instruction (1.5 cycles) later, reaches 0 after LOAD + 1 = 1000.
@ Each handler logs its letter, and stores its first cycle count and its SP at entry
@ at LOG + 0x100 (SysTick) or LOG + 0x108 (TIM2); the thread waits for both letters,
@ then exits.
.include "common.inc"
.text
vectors:
    vector_table unexpected,unexpected,unexpected,unexpected,unexpected,unexpected,unexpected,unexpected,unexpected,unexpected,unexpected,unexpected,unexpected, systick, unexpected,unexpected,unexpected,unexpected,unexpected,unexpected,unexpected,unexpected,unexpected,unexpected,unexpected,unexpected,unexpected,unexpected,unexpected,unexpected,unexpected,unexpected,unexpected,unexpected,unexpected,unexpected,unexpected,unexpected,unexpected,unexpected,unexpected,unexpected, tim2

.thumb_func
.global _start
_start:
    dwt_on
    ldr r0, =RCC_APB1ENR
    movs r1, #1
    str r1, [r0]
    ldr r0, =SHPR3 + 3
    movs r1, #0x80
    strb r1, [r0]
    ldr r0, =IPR + 28
    movs r1, #0x40
    strb r1, [r0]
    ldr r0, =ISER0
    mov.w r1, #0x10000000
    str r1, [r0]
    ldr r5, =TIM2
    movs r1, #1
    str r1, [r5, #0x0C]
    ldr r0, =0x20001000
    ldr r1, [r0]
    addw r1, r1, #1000
    str r1, [r5, #0x2C]
    ldr r6, =SYST_RVR
    movw r1, #999
    str r1, [r6]
    ldr r6, =SYST_CVR
    str r1, [r6]
    ldr r6, =SYST_CSR
    movs r2, #7
    movs r1, #1
    str r1, [r5]
    str r2, [r6]
wait:
    ldr r0, =LOG
    ldr r1, [r0]
    cmp r1, #2
    blt wait
    exit_ok

.thumb_func
systick:
    mov r12, sp
    ldr r3, =CYCCNT
    ldr r3, [r3]
    push {lr}
    ldr r0, =SYST_CSR
    movs r1, #0
    str r1, [r0]
    ldr r0, =LOG + 0x100
    str r3, [r0]
    str r12, [r0, #4]
    LOGI 'S'
    pop {pc}

.thumb_func
tim2:
    mov r12, sp
    ldr r3, =CYCCNT
    ldr r3, [r3]
    push {lr}
    ldr r0, =TIM2
    movs r1, #0
    str r1, [r0, #0x10]
    str r1, [r0]
    ldr r0, =LOG + 0x108
    str r3, [r0]
    str r12, [r0, #4]
    LOGI 'T'
    pop {pc}
.ltorg
