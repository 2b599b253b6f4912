#!/usr/bin/env python3
"""Per-program figures of the step pipeline from measure.py's JSON, and the goals.

Prints, per program: step events, the step interrupt's worst and mean instructions,
interrupts per step event, segment preparation per step event, preparation plus
interrupt per step event, and the step-event rate that the cost model sustains. Exits
non-zero when a program ends in the wrong place, the queue ran dry mid-job, the step
interrupt's worst exceeds its goal, or a program's preparation cannot sustain the
planner's step-rate cap even with all of the CPU (docs: bench/isr-cost/README.md).

Issue 14's average goal (GOAL_PIPELINE) is printed, met or not, but does not fail the
run: that issue ended blocked with the goal unmet (the flash budget left no room for
more fast paths), and a check that fails on every run hides every other result. What
bounds the product is the planner cap, and that one fails the run.
"""
import json, re, sys
from pathlib import Path

# The programs in the order of the bench's PROGRAMS (src/main.rs), with the end
# position each must reach (steps).
PROGRAMS = [
    ('star', (0, 0)),
    ('circle', (0, 0)),
    ('sine', (5024, -5)),
    ('spiral', (-1600, -1600)),
    ('fast', (0, 0)),
]
# Goals (issue 14): preparation plus interrupt per step event, on average over the
# programs; the step interrupt at its worst. The worst was 100 until the step output
# stopped depending on the interrupt's deadline (issue 20): restarting the one-pulse
# timer on its schedule, and the halt check after the restart that keeps an e-stop
# from being undone, cost 16 instructions, and a pulse that can never be repeated is
# worth them. The bound stays a bound: 120.
GOAL_PIPELINE = 250
GOAL_ISR_WORST = 120
# Cost model (README): cycles = 1.5 per instruction + 24 per interrupt (entry and exit).
CPI, IRQ_CYCLES, HZ = 1.5, 24, 72e6


def planner_cap():
    """MAX_STEP_RATE from the core: the rate the planner never lets a block exceed."""
    src = Path(__file__).resolve().parents[2] / 'core/src/stepper/mod.rs'
    m = re.search(r'pub const MAX_STEP_RATE: f32 = ([0-9_.]+);', src.read_text())
    if not m:
        sys.exit(f'MAX_STEP_RATE not found in {src}')
    return float(m.group(1).replace('_', ''))


def s32(v):
    return v - (1 << 32) if v >= 1 << 31 else v


def main(path):
    r = json.load(open(path))
    w = r['bench_result_words']
    per = r['per_program']
    n = len(PROGRAMS)
    bad = []
    rows = []
    print('| program | step events | ISR worst / mean | IRQs per event | prep per event | prep + ISR per event | sustained (100 % CPU) |')
    print('|---|---|---|---|---|---|---|')
    tot_pipe = 0.0
    isr_worst = 0
    cap = planner_cap()
    for i, (name, want_end) in enumerate(PROGRAMS):
        ev, irq, x, y, _, dry, _, _ = w[8 * i: 8 * i + 8]
        end = (s32(x), s32(y))
        f = per.get(str(i), {})
        tick = f.get('bench_isr_update', {'calls': 0, 'total': 0, 'worst': 0})
        prep = f.get('bench_prepare', {'calls': 0, 'total': 0, 'worst': 0})
        pend = f.get('bench_isr_pend', {'calls': 0, 'total': 0, 'worst': 0})
        ev1 = max(ev, 1)
        isr_mean = tick['total'] / max(tick['calls'], 1)
        prep_ev = (prep['total'] + pend['total']) / ev1
        isr_ev = tick['total'] / ev1
        pipe = prep_ev + isr_ev
        cycles = CPI * pipe + IRQ_CYCLES * irq / ev1
        rate = HZ / cycles
        isr_worst = max(isr_worst, tick['worst'])
        tot_pipe += pipe
        print(f"| {name} | {ev} | {tick['worst']} / {isr_mean:.1f} | {irq / ev1:.4f} | {prep_ev:.0f} | {pipe:.0f} | "
              f"{rate / 1e3:.0f} k/s |")
        if end != want_end or ev == 0:
            bad.append(f'{name}: ended at {end}, not {want_end} ({ev} step events)')
        if dry:
            bad.append(f'{name}: the step queue ran dry {dry} times before the job was done')
        if rate < cap:
            bad.append(f'{name}: {rate / 1e3:.0f} k/s with all of the CPU is below the planner cap '
                       f'MAX_STEP_RATE {cap / 1e3:.0f} k/s')
        rows.append(pipe)
    mean_pipe = tot_pipe / n
    print()
    print(f'preparation + interrupt: {mean_pipe:.0f} instructions per step event on average over the programs '
          f'(goal <= {GOAL_PIPELINE}); step interrupt worst {isr_worst} (goal <= {GOAL_ISR_WORST})')
    print(f'cost model: 1.5 cycles per instruction + {IRQ_CYCLES} per interrupt at 72 MHz; '
          f'every program must sustain the planner cap MAX_STEP_RATE {cap / 1e3:.0f} k/s')
    if mean_pipe > GOAL_PIPELINE:
        print(f'NOT MET (reported, not failed; issue 14 ended blocked): preparation + interrupt '
              f'{mean_pipe:.0f} > {GOAL_PIPELINE} instructions per step event on average')
    if isr_worst > GOAL_ISR_WORST:
        bad.append(f'step interrupt worst {isr_worst} > {GOAL_ISR_WORST} instructions')
    if bad:
        for b in bad:
            print('FAIL: ' + b)
        print(r.get('protocol_log_tail', '')[-400:])
        sys.exit(1)


if __name__ == '__main__':
    main(sys.argv[1])
