//! The SPU's run loops over compiled blocks ([`crate::jit`]): with the timing model off,
//! compiled blocks back to back, cold blocks through the interpreter's fast loop; with it
//! on, a memoized block's replay runs its compiled code and applies the block's timing
//! record exactly as the interpreter's replay does, so cycles, stalls and profiles are
//! the same. Everything else (channels, stops, interrupts, the quantum's end) goes back
//! to the general path.

use super::spu::Spu;
use crate::jit::{CodeCache, Engine, JitStats};

#[cfg(block_compiler)]
pub(super) type CompiledBlocks = crate::jit::Blocks;

/// No block compiler on this host.
#[cfg(not(block_compiler))]
pub(super) struct CompiledBlocks;

impl Spu {
    /// Chooses the engine (the interpreter where the host has no block compiler).
    pub fn set_engine(&mut self, engine: Engine) {
        self.engine = if Engine::SUPPORTED {
            engine
        } else {
            Engine::Interp
        };
    }

    /// The engine this SPU runs its code with.
    pub fn engine(&self) -> Engine {
        self.engine
    }

    /// Compiles into `cache`, shared with the other SPUs given it (so a block the SPUs
    /// share is compiled once); drops the blocks compiled so far. Results do not depend on
    /// it, only host time.
    pub fn share_code(&mut self, cache: &CodeCache) {
        #[cfg(block_compiler)]
        {
            // A generation after every one the SPU's timing memo may have kept code of.
            let generation = self.compiled.as_ref().map_or(1, |b| b.generation + 1);
            self.compiled = Some(Box::new(crate::jit::Blocks::new(cache.clone(), generation)));
        }
        #[cfg(not(block_compiler))]
        let _ = cache;
    }

    /// What the block compiler did so far: the blocks compiled and the compile time are
    /// those of the SPU's code cache (shared by the SPUs given the same one), the
    /// instructions run compiled this SPU's own.
    pub fn jit_stats(&self) -> JitStats {
        #[cfg(block_compiler)]
        let base = self
            .compiled
            .as_ref()
            .map(|b| b.cache().stats())
            .unwrap_or_default();
        #[cfg(not(block_compiler))]
        let base = JitStats::default();
        JitStats {
            compiled_instructions: self.compiled_instructions,
            steady_passes: self.steady_passes,
            ..base
        }
    }
}

#[cfg(not(block_compiler))]
impl Spu {
    pub(super) fn run_compiled(&mut self, until: u64) {
        self.run_fast(until)
    }

    pub(super) fn replay_compiled(
        &mut self,
        _pc: u32,
        _n: usize,
        _memo: usize,
        _until: u64,
    ) -> bool {
        false
    }
}

#[cfg(block_compiler)]
mod host {
    use super::super::spu::{invalidate_quad, Spu};
    use crate::analysis::is_branch;
    use crate::codec::Inst;
    use crate::jit::{
        asked, Blocks, CodeCache, Ctx, Entry, Lookup, MAX_BLOCK, RESULT_PARTIAL, RESULT_TAKEN,
    };
    use crate::machine::exec::{TruncatingFloats, LS_MASK, LS_SIZE};
    use crate::table::Op;
    use crate::timing::ends_block;
    use std::sync::atomic::Ordering;

    /// A block is compiled when it has started this often without compiled code: blocks
    /// entered only now and then (the rest of a block cut by a quantum's end, by a store
    /// into it) stay interpreted rather than compiled again and again.
    const HOT: u8 = 16;
    /// Starts of a block waiting for the background compiler counted before they are
    /// added to its demand.
    const DEMAND_BATCH: u32 = 16;
    /// A slot whose block the compiler declined: interpreted from then on.
    const DECLINED: u32 = u32::MAX;
    /// What a memo record keeps of its compiled block ([`crate::timing::Timing::memo_code`]):
    /// the block table's generation, these flags, the entry.
    const KEPT: u64 = 1;
    const KEPT_SELF_LOOP: u64 = 2;
    const KEPT_BRANCH: u64 = 4;

    /// After a compiled store into a quadword that may hold decoded code: marks it stale
    /// (bumping the code epoch if it held any) and says whether the block must end (the
    /// store wrote its own remaining instructions), as the interpreter's replay decides.
    unsafe extern "C" fn store_hook(
        ctx: *mut Ctx,
        addr: u32,
        next: u32,
        block_end: u32,
        more: u32,
    ) -> u32 {
        // SAFETY: the block was called by `Spu::call_block` with `spu` pointing at the
        // SPU, which nothing else uses during the call.
        let spu = unsafe { &mut *((*ctx).spu as *mut Spu) };
        if invalidate_quad(&mut spu.decoded, &mut spu.code_quads, addr) {
            spu.code_epoch += 1;
            // The block's words may have changed: no further pass of a self-loop.
            unsafe { (*ctx).budget = 0 };
        }
        let line = addr & LS_MASK & !15;
        (more != 0 && line < block_end && line + 16 > next) as u32
    }

    impl Spu {
        /// How many instructions a block starting at `pc` holds: up to and including the
        /// first branch, before anything that ends a block, at most [`MAX_BLOCK`].
        fn block_from(&mut self, pc: u32, out: Option<&mut Vec<Inst>>) -> usize {
            let mut n = 0;
            let mut p = pc;
            let mut out = out;
            while n < MAX_BLOCK {
                let inst = self.fetch(p);
                if ends_block(inst) || inst.op == Op::Bisled {
                    break;
                }
                if let Some(out) = out.as_mut() {
                    out.push(inst);
                }
                n += 1;
                if is_branch(inst.op) {
                    break;
                }
                p = (p + 4) & LS_MASK;
            }
            n
        }

        /// Whether local store still holds block `id`'s words at `pc`.
        fn block_still_there(&mut self, pc: u32, words: &[u32]) -> bool {
            words.iter().enumerate().all(|(k, &word)| {
                let inst = self.fetch(pc.wrapping_add(4 * k as u32) & LS_MASK);
                inst.word == word && !ends_block(inst) && inst.op != Op::Bisled
            })
        }

        /// The compiled block starting at `pc` (with `n` instructions, when given),
        /// compiling it if it is hot and `whole` (not the rest of a cut block); `None`:
        /// interpret it. The common case (compiled, checked at this code epoch) inline.
        #[inline(always)]
        fn compiled_block(&mut self, pc: u32, n: Option<usize>, whole: bool) -> Option<usize> {
            if let Some(blocks) = self.compiled.as_deref() {
                let slot = blocks.slots[(pc as usize >> 2) & (LS_SIZE / 4 - 1)];
                if slot != 0 && slot != DECLINED {
                    let id = slot as usize - 1;
                    let b = &blocks.blocks[id];
                    if b.verified == self.code_epoch && n.is_none_or(|n| b.code.n as usize == n) {
                        return Some(id);
                    }
                }
            }
            self.compiled_block_slow(pc, n, whole)
        }

        /// [`Spu::compiled_block`] past its common case: checking the words again after
        /// the code epoch moved, counting heat, compiling.
        #[inline(never)]
        fn compiled_block_slow(&mut self, pc: u32, n: Option<usize>, whole: bool) -> Option<usize> {
            let w = (pc as usize >> 2) & (LS_SIZE / 4 - 1);
            let blocks = self
                .compiled
                .get_or_insert_with(|| Box::new(Blocks::new(CodeCache::new(), 1)));
            let slot = blocks.slots[w];
            if slot == DECLINED {
                return None;
            }
            if slot != 0 {
                let id = slot as usize - 1;
                let b = &blocks.blocks[id];
                if n.is_none_or(|n| b.code.n as usize == n) {
                    if b.verified == self.code_epoch {
                        return Some(id);
                    }
                    let code = b.code.clone();
                    if self.block_still_there(pc, &code.words) {
                        let epoch = self.code_epoch;
                        self.compiled.as_mut().expect("blocks").blocks[id].verified = epoch;
                        return Some(id);
                    }
                }
                self.compiled.as_mut().expect("blocks").slots[w] = 0;
            }
            let blocks = self.compiled.as_mut().expect("blocks");
            if !whole {
                return None;
            }
            blocks.heat[w] = blocks.heat[w].saturating_add(1);
            if blocks.heat[w] < HOT {
                return None;
            }
            // Queued for the background compiler: asked again once it finished a block.
            if blocks.pending[w] == asked(blocks.cache().completed()) {
                if let Some((demand, starts)) = blocks.demand.get_mut(&(w as u32)) {
                    // Told to the compiler in batches: SPUs on other threads count the
                    // same block, and one shared counter bumped at every start would be
                    // fought over.
                    *starts += 1;
                    if *starts % DEMAND_BATCH == 0 {
                        demand.fetch_add(DEMAND_BATCH as u64, Ordering::Relaxed);
                    }
                }
                return None;
            }
            let mut insts = Vec::new();
            match n {
                Some(n) => {
                    for k in 0..n {
                        insts.push(self.fetch(pc.wrapping_add(4 * k as u32) & LS_MASK));
                    }
                }
                None => {
                    self.block_from(pc, Some(&mut insts));
                }
            }
            let epoch = self.code_epoch;
            let blocks = self.compiled.as_mut().expect("blocks");
            let completed = blocks.cache().completed();
            match blocks.compile(pc, &insts, store_hook) {
                Ok(id) => {
                    blocks.heat[w] = 0;
                    blocks.pending[w] = 0;
                    blocks.demand.remove(&(w as u32));
                    blocks.blocks[id].verified = epoch;
                    Some(id)
                }
                Err(Lookup::Pending(demand)) => {
                    blocks.pending[w] = asked(completed);
                    // (the same block asked again keeps its count; another at this
                    // address, of another length, starts its own)
                    match blocks.demand.get(&(w as u32)) {
                        Some((known, _)) if std::sync::Arc::ptr_eq(known, &demand) => {}
                        _ => {
                            blocks.demand.insert(w as u32, (demand, 0));
                        }
                    }
                    None
                }
                Err(_) => {
                    blocks.heat[w] = 0;
                    blocks.pending[w] = 0;
                    blocks.demand.remove(&(w as u32));
                    if n.is_none() {
                        blocks.slots[w] = DECLINED;
                    }
                    None
                }
            }
        }

        /// Runs compiled block `id` with a `budget` of instructions (a self-looping block
        /// runs again while a whole pass fits); returns its result word, its final
        /// branch's target, the passes before the last (each back to the start) and the
        /// instructions done.
        #[inline(always)]
        fn call_block(&mut self, id: usize, budget: u64) -> (u64, u32, u64, u64) {
            let code = &self.compiled.as_ref().expect("blocks").blocks[id].code;
            let (entry, n) = (code.entry, code.n as u64);
            // SAFETY: the block's code is held by this SPU's block table.
            unsafe { self.call_entry(entry, n, budget) }
        }

        /// [`Spu::call_block`] with the block's entry and length at hand.
        ///
        /// # Safety
        /// `entry` is the entry of a block of `n` instructions that this SPU's block table
        /// holds (so its code memory is alive).
        #[inline(always)]
        unsafe fn call_entry(&mut self, entry: Entry, n: u64, budget: u64) -> (u64, u32, u64, u64) {
            let spu: *mut Spu = self;
            // SAFETY: every pointer is derived from the exclusively borrowed SPU and used
            // only during the call; the block's code is owned by its cache, which stays
            // alive (compiling happens only outside calls).
            unsafe {
                let mut ctx = Ctx {
                    regs: (*spu).core.regs.as_mut_ptr(),
                    ls: (*spu).core.ls.as_mut_ptr(),
                    code_quads: (*spu).code_quads.as_mut_ptr(),
                    core: &mut (*spu).core,
                    spu: spu as *mut u8,
                    target: 0,
                    _pad: 0,
                    budget,
                    loops: 0,
                };
                let r = entry(&mut ctx);
                (
                    r,
                    ctx.target,
                    ctx.loops,
                    ctx.loops * n + ((r >> 32) & 0xffff),
                )
            }
        }

        /// Timing off: compiled blocks back to back while the clock is before `until`, the
        /// interpreter's fast loop for blocks not compiled (yet). Returns at anything for
        /// the general path (a channel, stop, interrupt, ...), at `until`, or when the
        /// interpreter stopped early.
        #[inline(never)]
        pub(in crate::machine) fn run_compiled(&mut self, until: u64) {
            let truncating = TruncatingFloats::hold();
            while self.cycle < until && !self.core.interrupts_enabled {
                let pc = self.pc;
                let budget = until - self.cycle;
                // Where the last block was cut short (by the quantum's end or a store into
                // it), this is the rest of a block, which is not made a block of its own.
                let whole = !std::mem::take(&mut self.block_cut);
                if let Some(id) = self.compiled_block(pc, None, whole) {
                    let n = self.compiled.as_ref().expect("blocks").blocks[id].code.n as u64;
                    if n <= budget {
                        let (r, _, _, done) = self.call_block(id, budget);
                        // (Left at an inner branch, taken: not cut.)
                        self.block_cut = r & (RESULT_PARTIAL | RESULT_TAKEN) == RESULT_PARTIAL;
                        self.pc = r as u32;
                        self.instructions += done;
                        self.cycle += done;
                        self.compiled_instructions += done;
                        continue;
                    }
                }
                let n = self.block_from(pc, None) as u64;
                if n == 0 {
                    break;
                }
                self.block_cut = n > budget;
                let stop = self.cycle + n.min(budget);
                self.run_fast(stop);
                if self.cycle < stop {
                    break;
                }
            }
            truncating.release();
        }

        /// Timing on: runs the memoized block `memo` (`n` instructions at `pc`, its replay
        /// just started) as compiled code and applies its timing record; false (nothing
        /// done) when it has no compiled code. A block whose branch went back to its start
        /// in a steady state ([`crate::timing::Timing::steady_passes`]) then runs pass
        /// after pass inside its compiled code, its record applied once for them all,
        /// while the passes start before `until`.
        pub(in crate::machine) fn replay_compiled(
            &mut self,
            pc: u32,
            n: usize,
            memo: usize,
            until: u64,
        ) -> bool {
            // The compiled code kept with the record (its words are the record's, which
            // the caller found in local store), else the block table's.
            let generation = self.compiled.as_ref().map_or(0, |b| b.generation);
            let timing = self.timing.as_ref().expect("timing");
            let [g, flags, entry] = timing.memo_code(memo);
            let (entry, flags) = if g == generation && flags != 0 {
                // SAFETY: kept below from a block the table of this generation holds.
                (
                    unsafe { std::mem::transmute::<usize, Entry>(entry as usize) },
                    flags,
                )
            } else {
                let Some(id) = self.compiled_block(pc, Some(n), true) else {
                    return false;
                };
                let blocks = self.compiled.as_ref().expect("blocks");
                let code = &blocks.blocks[id].code;
                let flags = KEPT
                    | (code.self_loop as u64 * KEPT_SELF_LOOP)
                    | (is_branch(code.last.op) as u64 * KEPT_BRANCH);
                let kept = [blocks.generation, flags, code.entry as usize as u64];
                let entry = code.entry;
                self.timing
                    .as_mut()
                    .expect("timing")
                    .set_memo_code(memo, kept);
                (entry, flags)
            };
            // Blocks hold no `bisled`, the one reader of the pending-event flag.
            self.core.event_pending_known = false;
            // One pass (its timing record applied), then more in one go if steady.
            // SAFETY: `entry` is a block of `n` instructions the block table holds.
            let (r, target, _, done) = unsafe { self.call_entry(entry, n as u64, 0) };
            self.compiled_pass_done(pc, n, memo, flags, 0, r, target, done);
            if r & (RESULT_PARTIAL | RESULT_TAKEN) != RESULT_TAKEN
                || target != pc
                || flags & KEPT_SELF_LOOP == 0
            {
                return true;
            }
            let first = self.decoded[(pc as usize >> 2) & (LS_SIZE / 4 - 1)];
            let timing = self.timing.as_mut().expect("timing");
            // The passes stop only at their end: under a cycle limit the last starts where a
            // whole one still ends before it, as a single replay must (`Spu::replay_fits`),
            // so that the per-instruction path stops the clock at the limit exactly.
            let until = match self.limit {
                u64::MAX => until,
                limit => until.min(
                    limit.saturating_sub(
                        timing
                            .memo_span(memo)
                            .saturating_add(super::super::spu::LIMIT_REACH),
                    ),
                ),
            };
            let passes = timing.steady_passes(memo, pc, first, until);
            if passes < 2 {
                return true;
            }
            // SAFETY: as above.
            let (r, target, loops, done) =
                unsafe { self.call_entry(entry, n as u64, passes * n as u64) };
            self.steady_passes += loops + 1;
            self.compiled_pass_done(pc, n, memo, flags, loops, r, target, done);
            true
        }

        /// Applies the timing record of memo `memo` to `loops` passes of compiled block
        /// `id` (`n` instructions at `pc`) that went back to its start in a steady state,
        /// and to the pass after them, which returned `r` (its branch's `target`); `done`
        /// instructions in all.
        #[allow(clippy::too_many_arguments)]
        #[inline(always)]
        fn compiled_pass_done(
            &mut self,
            pc: u32,
            n: usize,
            memo: usize,
            flags: u64,
            loops: u64,
            r: u64,
            target: u32,
            done: u64,
        ) {
            let last_pc = pc.wrapping_add(4 * (n as u32 - 1)) & LS_MASK;
            let timing = self.timing.as_mut().expect("timing");
            timing.note_hint_target(self.core.hint_target);
            timing.steady_replayed(memo, loops, (last_pc, true, pc));
            if r & (RESULT_PARTIAL | RESULT_TAKEN) == RESULT_PARTIAL | RESULT_TAKEN {
                // Left at an inner branch, taken.
                let k = ((r >> 32) & 0xffff) as usize;
                let at = pc.wrapping_add(4 * (k as u32 - 1)) & LS_MASK;
                timing.block_left_at_branch(memo, k, at, target);
            } else if r & RESULT_PARTIAL != 0 {
                timing.block_replayed_partly(memo, ((r >> 32) & 0xffff) as usize);
            } else if flags & KEPT_BRANCH != 0 {
                let taken = r & RESULT_TAKEN != 0;
                timing.block_replayed(memo, Some((last_pc, taken, target)));
            } else {
                timing.block_replayed(memo, None);
            }
            self.pc = r as u32;
            self.instructions += done;
            self.compiled_instructions += done;
            self.cycle = timing.now();
        }
    }
}
