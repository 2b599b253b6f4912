#!/usr/bin/env python3
"""Count the instructions the real thumbv7m step-interrupt code executes, per call.

Runs a Cortex-M3 ELF (bench/isr-cost, built for thumbv7m-none-eabi) in the unicorn
emulator from its reset vector until it executes `bkpt`. Every basic block executed is
counted exactly (capstone decodes each block once); blocks executed between the entry of
a chosen function and the return to its caller are charged to that call. Emulation is
deterministic, so the counts are the same on every run and every machine.

Usage: measure.py ELF [--json OUT]
The ELF exports `bench_isr` (the firmware's whole TIM2 interrupt handler; each call is
classified by the timer's update flag at entry, see --split) and
`bench_prepare` (one call of the segment preparer), and a `BENCH_RESULT` record that
its main fills in (steps executed per program).
"""
import argparse, json, struct, sys
from elftools.elf.elffile import ELFFile
from unicorn import Uc, UC_ARCH_ARM, UC_MODE_THUMB, UC_MODE_MCLASS, UC_HOOK_BLOCK, UC_HOOK_INTR
from unicorn.arm_const import UC_ARM_REG_SP, UC_ARM_REG_LR, UC_ARM_REG_PC, UC_CPU_ARM_CORTEX_M3
from capstone import Cs, CS_ARCH_ARM, CS_MODE_THUMB, CS_MODE_MCLASS

FLASH, FLASH_SIZE = 0x0800_0000, 0x0010_0000
RAM, RAM_SIZE = 0x2000_0000, 0x0010_0000
PERIPH, PERIPH_SIZE = 0x4000_0000, 0x0010_0000      # GPIO/TIM registers: plain memory here
BITBAND, BITBAND_SIZE = 0x4200_0000, 0x0200_0000    # peripheral bit-band alias (the HAL uses it)
SCS, SCS_SIZE = 0xE000_0000, 0x0010_0000            # core peripherals: plain memory here


def symbols(elf):
    tab = elf.get_section_by_name('.symtab')
    return {s.name: (s['st_value'], s['st_size']) for s in tab.iter_symbols() if s.name}


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument('elf')
    ap.add_argument('--json')
    ap.add_argument('--names', default='bench_isr,bench_prepare')
    ap.add_argument('--callers-prog', type=int, help='with --callers: only in this program')
    ap.add_argument('--callers', help='with --profile: count the callers of functions whose name contains this')
    ap.add_argument('--profile', help='charge the instructions inside calls of NAME to the functions executing them')
    ap.add_argument('--split', action='append', default=['bench_isr=0x40000010:1:update:pend'],
                    help='NAME=REG:MASK:YES:NO charges NAME to NAME_YES if (*REG & MASK) at entry, else NAME_NO')
    args = ap.parse_args()

    with open(args.elf, 'rb') as f:
        elf = ELFFile(f)
        syms = symbols(elf)
        uc = Uc(UC_ARCH_ARM, UC_MODE_THUMB | UC_MODE_MCLASS)
        uc.ctl_set_cpu_model(UC_CPU_ARM_CORTEX_M3)
        for base, size in ((FLASH, FLASH_SIZE), (RAM, RAM_SIZE), (PERIPH, PERIPH_SIZE), (BITBAND, BITBAND_SIZE), (SCS, SCS_SIZE)):
            uc.mem_map(base, size)
        for seg in elf.iter_segments():
            if seg['p_type'] == 'PT_LOAD' and seg['p_filesz']:
                uc.mem_write(seg['p_paddr'], seg.data())
        image = bytes(uc.mem_read(FLASH, FLASH_SIZE))

    sp, reset = struct.unpack_from('<II', image, 0)
    names = args.names.split(',')
    entries = {}
    for n in names:
        if n not in syms:
            sys.exit(f'symbol {n} not found in {args.elf}')
        entries[syms[n][0] & ~1] = n
    cs = Cs(CS_ARCH_ARM, CS_MODE_THUMB | CS_MODE_MCLASS)
    block_len = {}
    split = {}
    for spec in args.split:
        name, rest = spec.split('=')
        reg, mask, yes, no = rest.split(':')
        if name in names:
            split[name] = (int(reg, 0), int(mask, 0), f'{name}_{yes}', f'{name}_{no}')
    counted = [n for n in names if n not in split] + [x for v in split.values() for x in v[2:]]
    stats = {n: {'calls': 0, 'total': 0, 'worst': 0, 'hist': {}} for n in counted}
    state = {'fn': None, 'ret': None, 'count': 0, 'all': 0, 'prog': 0}
    # Every call is also charged to the program running (the bench's BENCH_PROGRAM).
    prog_addr = syms.get('BENCH_PROGRAM', (None, 0))[0]
    per_prog = {}
    # Function (symbol) containing each address, for --profile.
    funcs = sorted((v[0] & ~1, v[0] & ~1 + 0, v[1], k) for k, v in syms.items() if v[1] > 0)
    import bisect
    starts = [f[0] for f in funcs]
    prof = {}
    prof_of = {}
    # Calls of each function inside the profiled calls (blocks at its entry).
    entry_of = {a: name for a, _, size, name in funcs}
    entered = {}
    callers = {}
    prof_prog = {}
    entered_prog = {}

    def owner(addr):
        i = bisect.bisect_right(starts, addr) - 1
        while i >= 0:
            a, _, size, name = funcs[i]
            if a <= addr < a + size:
                return name
            i -= 1
            if i >= 0 and funcs[i][0] + 4096 < addr:
                break
        # No sized symbol covers it: the nearest symbol before it.
        near = max(((a, n) for n, (a, _) in syms.items() if (a & ~1) <= addr), default=(0, '?'))
        return '~' + near[1]

    def on_block(uc, addr, size, _):
        n = block_len.get((addr, size))
        if n is None:
            code = bytes(uc.mem_read(addr, size))
            n = sum(1 for _ in cs.disasm_lite(code, addr))
            block_len[(addr, size)] = n
        state['all'] += n
        if state['fn'] is not None and addr == state['ret']:
            s = stats[state['fn']]
            c = state['count']
            s['calls'] += 1
            s['total'] += c
            s['worst'] = max(s['worst'], c)
            s['hist'][c] = s['hist'].get(c, 0) + 1
            pp = per_prog.setdefault(state['prog'], {}).setdefault(state['fn'], {'calls': 0, 'total': 0, 'worst': 0})
            pp['calls'] += 1
            pp['total'] += c
            pp['worst'] = max(pp['worst'], c)
            state['fn'] = None
        if state['fn'] is None and addr in entries:
            state['fn'] = entries[addr]
            if state['fn'] in split:
                # Classify the call by a status register at entry (e.g. the timer's UIF).
                reg, bit, yes, no = split[state['fn']]
                flags = struct.unpack('<I', bytes(uc.mem_read(reg, 4)))[0]
                state['fn'] = yes if flags & bit else no
            state['ret'] = uc.reg_read(UC_ARM_REG_LR) & ~1
            if prog_addr is not None:
                state['prog'] = struct.unpack('<I', bytes(uc.mem_read(prog_addr, 4)))[0]
            state['count'] = 0
        if state['fn'] is not None:
            state['count'] += n
            if args.profile and state['fn'].startswith(args.profile):
                o = prof_of.get(addr)
                if o is None:
                    o = prof_of[addr] = owner(addr)
                prof[o] = prof.get(o, 0) + n
                pp = prof_prog.setdefault(state['prog'], {})
                pp[o] = pp.get(o, 0) + n
                if addr in entry_of:
                    entered[entry_of[addr]] = entered.get(entry_of[addr], 0) + 1
                    if args.callers and args.callers in entry_of[addr] and (args.callers_prog is None or state['prog'] == args.callers_prog):
                        lr = uc.reg_read(UC_ARM_REG_LR) & ~1
                        c = owner(lr)
                        if c.startswith('OUTLINED'):
                            c = c + ' (outlined)'
                        callers[c] = callers.get(c, 0) + 1
                    ep = entered_prog.setdefault(state['prog'], {})
                    ep[entry_of[addr]] = ep.get(entry_of[addr], 0) + 1

    def on_intr(uc, intno, _):
        uc.emu_stop()  # bkpt: the bench's main is done

    uc.hook_add(UC_HOOK_BLOCK, on_block)
    uc.hook_add(UC_HOOK_INTR, on_intr)
    uc.reg_write(UC_ARM_REG_SP, sp)
    uc.emu_start(reset | 1, 0xFFFF_FFFF, count=2_000_000_000)

    result = {'instructions_total': state['all'], 'functions': {}}
    for n, s in stats.items():
        mean = s['total'] / s['calls'] if s['calls'] else 0.0
        result['functions'][n] = {'calls': s['calls'], 'worst': s['worst'], 'mean': round(mean, 2), 'total': s['total'],
                                  'histogram': {str(k): v for k, v in sorted(s['hist'].items())}}
    result['per_program'] = {str(k): v for k, v in sorted(per_prog.items())}
    if 'BENCH_RESULT' in syms:
        addr, size = syms['BENCH_RESULT']
        words = struct.unpack(f'<{size // 4}I', bytes(uc.mem_read(addr, size)))
        result['bench_result_words'] = list(words)
    if 'BENCH_LOG' in syms:
        addr, size = syms['BENCH_LOG']
        result['protocol_log_tail'] = bytes(uc.mem_read(addr, size)).rstrip(b'\0').decode('ascii', 'replace')
    if args.profile:
        result['profile'] = dict(sorted(prof.items(), key=lambda kv: -kv[1]))
        result['profile_calls'] = entered
        result['callers'] = dict(sorted(callers.items(), key=lambda kv: -kv[1]))
        result['profile_calls_by_program'] = {str(k): v for k, v in entered_prog.items()}
        result['profile_by_program'] = {str(k): dict(sorted(v.items(), key=lambda kv: -kv[1])) for k, v in prof_prog.items()}
    if args.json:
        with open(args.json, 'w') as f:
            json.dump(result, f, indent=1)
    json.dump(result, sys.stdout, indent=1)
    print()


if __name__ == '__main__':
    main()
