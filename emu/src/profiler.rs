//! Instructions executed per function, symbolized from the ELF (`cargo emu run
//! --profile`): where the firmware's CPU time goes, per exception (RTIC runs each task
//! priority in its own dispatcher interrupt, so an exception is a task level).
//!
//! Counts come from the translated blocks the CPU runs (each block's instructions, at
//! its start). "Self" is the function whose code the block is in (inlined callees
//! count as their caller). "Inclusive" adds everything called from it: a shadow call
//! stack per exception, pushed when a block starts at a function's first instruction
//! (its return address is LR then; a tail call pushes a frame with the same return
//! address) and popped, with any frame above it, when a block starts at a return
//! address on the stack (frames entered by a branch with a stale LR). Exception
//! entry (LR holds EXC_RETURN) starts that exception's stack afresh.

use crate::elf::Image;
use object::{Object, ObjectSymbol, SymbolKind};
use std::collections::HashMap;

#[derive(Clone, Copy)]
struct Frame {
    func: usize,
    ret: u32,
}

pub struct Profiler {
    names: Vec<String>,
    /// (start, end, function) sorted by start.
    ranges: Vec<(u32, u32, usize)>,
    starts: HashMap<u32, usize>,
    /// Function of each block address seen (None: outside every symbol).
    block_func: HashMap<u32, Option<usize>>,
    stacks: Vec<Vec<Frame>>,
    /// (exception, function) -> instructions.
    self_count: HashMap<(usize, usize), u64>,
    inclusive: HashMap<(usize, usize), u64>,
    /// (exception, function) -> calls (entries at its first instruction).
    calls: HashMap<(usize, usize), u64>,
    /// Instructions per exception.
    total: Vec<u64>,
}

impl Profiler {
    pub fn new(image: &Image, exceptions: usize) -> Result<Profiler, String> {
        let file = object::File::parse(&*image.bytes).map_err(|e| e.to_string())?;
        let mut names = Vec::new();
        let mut ranges = Vec::new();
        let mut starts = HashMap::new();
        for s in file.symbols() {
            if s.kind() != SymbolKind::Text || s.size() == 0 {
                continue;
            }
            let Ok(name) = s.name() else { continue };
            let start = (s.address() as u32) & !1;
            if starts.contains_key(&start) {
                continue;
            }
            let i = names.len();
            names.push(format!("{:#}", rustc_demangle::demangle(name)));
            ranges.push((start, start + s.size() as u32, i));
            starts.insert(start, i);
        }
        ranges.sort_unstable();
        Ok(Profiler {
            names,
            ranges,
            starts,
            block_func: HashMap::new(),
            stacks: vec![Vec::new(); exceptions],
            self_count: HashMap::new(),
            inclusive: HashMap::new(),
            calls: HashMap::new(),
            total: vec![0; exceptions],
        })
    }

    fn func_of(&mut self, addr: u32) -> Option<usize> {
        let ranges = &self.ranges;
        *self.block_func.entry(addr).or_insert_with(|| {
            let k = ranges.partition_point(|&(s, _, _)| s <= addr);
            let &(s, e, f) = ranges.get(k.checked_sub(1)?)?;
            (s..e).contains(&addr).then_some(f)
        })
    }

    /// A block of `n` instructions at `addr` is about to run in exception `exc`; `lr`
    /// is the link register now.
    pub fn block(&mut self, exc: usize, addr: u32, n: u32, lr: u32) {
        let Some(stack) = self.stacks.get_mut(exc) else {
            return;
        };
        if let Some(&func) = self.starts.get(&addr) {
            if lr >= 0xFFFF_FF00 {
                stack.clear();
            }
            let ret = lr & !1;
            let top = stack.last().copied();
            if !top.is_some_and(|t| t.func == func && t.ret == ret) {
                stack.push(Frame { func, ret });
                *self.calls.entry((exc, func)).or_default() += 1;
            }
        } else if let Some(k) = stack.iter().rposition(|t| t.ret == addr) {
            // A return: to this frame's caller. Frames above it that never saw their
            // return (entered by a branch with a stale LR) go with it.
            stack.truncate(k);
        }
        let n = u64::from(n);
        let own = self.func_of(addr);
        let stack = &self.stacks[exc];
        let mut seen: Vec<usize> = stack.iter().map(|f| f.func).chain(own).collect();
        seen.sort_unstable();
        seen.dedup();
        for f in seen {
            *self.inclusive.entry((exc, f)).or_default() += n;
        }
        if let Some(f) = own {
            *self.self_count.entry((exc, f)).or_default() += n;
        }
        self.total[exc] += n;
    }

    /// The `top` functions of each exception that ran, by inclusive count, as text;
    /// `per` divides every figure (for example by the lines streamed).
    pub fn report(&self, top: usize, per: f64, per_what: &str) -> String {
        let mut out = String::new();
        for (exc, &total) in self.total.iter().enumerate() {
            if total == 0 {
                continue;
            }
            let what = if exc == 0 {
                "thread mode".to_string()
            } else if exc >= 16 {
                format!("IRQ {}", exc - 16)
            } else {
                format!("exception {exc}")
            };
            out += &format!(
                "\n{what}: {total} instructions, {:.0} per {per_what}\n{:>12} {:>12} {:>9} {:>10}  function (per {per_what}; calls; inclusive per call)\n",
                total as f64 / per,
                "inclusive",
                "self",
                "calls",
                "per call"
            );
            let mut rows: Vec<(u64, usize)> = self
                .inclusive
                .iter()
                .filter(|((e, _), _)| *e == exc)
                .map(|(&(_, f), &c)| (c, f))
                .collect();
            rows.sort_unstable_by(|a, b| b.cmp(a));
            let mut by_self: Vec<(u64, usize)> = rows
                .iter()
                .map(|&(_, f)| (self.self_count.get(&(exc, f)).copied().unwrap_or(0), f))
                .collect();
            by_self.sort_unstable_by(|a, b| b.cmp(a));
            for (order, list) in [("by inclusive", rows), ("by self", by_self)] {
                out += &format!("  {order}:\n");
                for (_, f) in list.into_iter().take(top) {
                    let all = self.inclusive.get(&(exc, f)).copied().unwrap_or(0);
                    let own = self.self_count.get(&(exc, f)).copied().unwrap_or(0);
                    let calls = self.calls.get(&(exc, f)).copied().unwrap_or(0);
                    out += &format!(
                        "{:>12.0} {:>12.0} {:>9.2} {:>10.0}  {}\n",
                        all as f64 / per,
                        own as f64 / per,
                        calls as f64 / per,
                        all as f64 / calls.max(1) as f64,
                        self.names[f]
                    );
                }
            }
        }
        out
    }
}
